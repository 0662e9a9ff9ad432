#include "frontend/fabmap.h"

#include <algorithm>
#include <cmath>
#include <utility>
#include <limits>
#include <stdexcept>
#include <string>

namespace catgraph {
namespace {

// openFABMAP's smoothing of every learned probability into [0.01, 0.99].
double Smooth(double frequency) { return 0.98 * frequency + 0.01; }

std::vector<char> Presence(const WordSet& words, int vocabulary_size) {
  std::vector<char> present(static_cast<std::size_t>(vocabulary_size), 0);
  for (const int w : words) {
    if (w < 0 || w >= vocabulary_size) {
      throw std::invalid_argument("word id " + std::to_string(w) + " outside the vocabulary of " +
                                  std::to_string(vocabulary_size) + " words");
    }
    present[static_cast<std::size_t>(w)] = 1;
  }
  return present;
}

}  // namespace

double MutualInformation(double n, double n_a, double n_b, double n_ab) {
  const double p_a = n_a / n, p_b = n_b / n;
  const double joint[4] = {n_ab / n, (n_a - n_ab) / n, (n_b - n_ab) / n, (n - n_a - n_b + n_ab) / n};
  const double marginal[4] = {p_a * p_b, p_a * (1 - p_b), (1 - p_a) * p_b, (1 - p_a) * (1 - p_b)};
  double mi = 0.0;
  for (int i = 0; i < 4; ++i) {
    if (joint[i] > 0.0) mi += joint[i] * std::log(joint[i] / marginal[i]);
  }
  return mi;
}

ChowLiuTree LearnChowLiuTree(const std::vector<WordSet>& training, int vocabulary_size) {
  if (training.empty()) throw std::invalid_argument("Chow-Liu tree: no training observations");
  if (vocabulary_size < 1) throw std::invalid_argument("Chow-Liu tree: empty vocabulary");
  const auto v = static_cast<std::size_t>(vocabulary_size);
  std::vector<double> count(v, 0.0);
  std::vector<std::uint32_t> both(v * v, 0);  // co-occurrence counts, symmetric
  for (const WordSet& words : training) {
    Presence(words, vocabulary_size);  // range check
    for (std::size_t i = 0; i < words.size(); ++i) {
      const auto a = static_cast<std::size_t>(words[i]);
      count[a] += 1.0;
      for (std::size_t j = i + 1; j < words.size(); ++j) {
        const auto b = static_cast<std::size_t>(words[j]);
        ++both[a * v + b];
        ++both[b * v + a];
      }
    }
  }
  const double n = static_cast<double>(training.size());
  auto mi = [&](std::size_t a, std::size_t b) {
    return MutualInformation(n, count[a], count[b], static_cast<double>(both[a * v + b]));
  };

  // Prim's algorithm for the maximum spanning tree on the dense MI graph.
  ChowLiuTree tree;
  tree.parent.assign(v, -1);
  std::vector<double> best(v, -std::numeric_limits<double>::infinity());
  std::vector<char> in_tree(v, 0);
  std::size_t current = 0;
  in_tree[0] = 1;
  for (std::size_t added = 1; added < v; ++added) {
    std::size_t next = v;
    for (std::size_t q = 0; q < v; ++q) {
      if (in_tree[q]) continue;
      const double m = mi(current, q);
      if (m > best[q]) best[q] = m, tree.parent[q] = static_cast<int>(current);
      if (next == v || best[q] > best[next]) next = q;
    }
    in_tree[next] = 1;
    current = next;
  }

  tree.p_z.resize(v);
  tree.p_z_given_parent_on.resize(v);
  tree.p_z_given_parent_off.resize(v);
  for (std::size_t q = 0; q < v; ++q) {
    tree.p_z[q] = Smooth(count[q] / n);
    const int p = tree.parent[q];
    if (p < 0) {
      tree.p_z_given_parent_on[q] = tree.p_z_given_parent_off[q] = tree.p_z[q];
      continue;
    }
    const auto pp = static_cast<std::size_t>(p);
    const double n_both = both[q * v + pp];
    tree.p_z_given_parent_on[q] = count[pp] > 0 ? Smooth(n_both / count[pp]) : tree.p_z[q];
    tree.p_z_given_parent_off[q] =
        n - count[pp] > 0 ? Smooth((count[q] - n_both) / (n - count[pp])) : tree.p_z[q];
  }
  return tree;
}

void Validate(const FabMapOptions& o) {
  auto fail = [](const std::string& what) { throw std::invalid_argument("FabMapOptions: " + what); };
  if (!(o.p_observe_given_exists > 0.0 && o.p_observe_given_exists <= 1.0)) {
    fail("p_observe_given_exists must be in (0, 1]");
  }
  if (!(o.p_observe_given_absent >= 0.0 && o.p_observe_given_absent < 1.0)) {
    fail("p_observe_given_absent must be in [0, 1)");
  }
  if (!std::isfinite(o.new_place_log_offset)) fail("new_place_log_offset must be finite");
}

FabMapModel::FabMapModel(ChowLiuTree tree, FabMapOptions options, std::vector<WordSet> new_place_samples)
    : tree_(std::move(tree)), options_(options), samples_(std::move(new_place_samples)) {
  if (tree_.vocabulary_size() < 1) throw std::invalid_argument("FabMapModel: empty Chow-Liu tree");
  if (options_.new_place == NewPlaceModel::kSampled && samples_.empty()) {
    throw std::invalid_argument("FabMapModel: the sampled new place needs sample observations");
  }
  Validate(options_);
}

namespace {

class FabMapFrameScore : public FrameScore {
 public:
  // `words` (the frame's) must outlive the score.
  FabMapFrameScore(FrameLikelihood likelihood, const WordSet& words)
      : likelihood_(std::move(likelihood)), words_(words) {}
  double LogLikelihood(const Observation& node) const override { return likelihood_.LogLikelihood(node.words); }
  double LogNewPlaceLikelihood() const override { return likelihood_.LogNewPlaceLikelihood(); }
  double SelfEvidence() const override { return likelihood_.SelfEvidence(words_); }

 private:
  FrameLikelihood likelihood_;
  const WordSet& words_;
};

}  // namespace

std::unique_ptr<FrameScore> FabMapModel::ScoreFrame(const Observation& z,
                                                    const std::vector<const Observation*>& /*places*/) const {
  return std::make_unique<FabMapFrameScore>(ForFrame(z.words), z.words);
}

double FabMapModel::PExists(int q, bool location_has_word) const {
  const double p1 = tree_.p_z[static_cast<std::size_t>(q)];
  const double seen_if_exists =
      location_has_word ? options_.p_observe_given_exists : 1.0 - options_.p_observe_given_exists;
  const double seen_if_absent =
      location_has_word ? options_.p_observe_given_absent : 1.0 - options_.p_observe_given_absent;
  return seen_if_exists * p1 / (seen_if_exists * p1 + seen_if_absent * (1.0 - p1));
}

double FabMapModel::WordTerm(int q, double p_exists, bool z, bool z_parent) const {
  const auto i = static_cast<std::size_t>(q);
  auto p_z_given_e = [&](bool value, bool exists) {
    const double p1 = exists ? options_.p_observe_given_exists : options_.p_observe_given_absent;
    return value ? p1 : 1.0 - p1;
  };
  const double marginal = tree_.p_z[i];
  const double conditional = tree_.parent[i] < 0
                                 ? marginal
                                 : (z_parent ? tree_.p_z_given_parent_on[i] : tree_.p_z_given_parent_off[i]);
  double sum = 0.0;
  for (const bool e : {false, true}) {
    double p;
    if (options_.naive_bayes) {
      p = p_z_given_e(z, e);
    } else {
      const double p_value = z ? marginal : 1.0 - marginal;
      const double p_value_given_parent = z ? conditional : 1.0 - conditional;
      const double alpha = p_value * p_z_given_e(!z, e) * (1.0 - p_value_given_parent);
      const double beta = (1.0 - p_value) * p_z_given_e(z, e) * p_value_given_parent;
      p = alpha + beta > 0.0 ? beta / (alpha + beta) : 0.0;
    }
    sum += (e ? p_exists : 1.0 - p_exists) * p;
  }
  return std::log(sum);
}

FrameLikelihood FabMapModel::ForFrame(const WordSet& z) const {
  const std::vector<char> present = Presence(z, vocabulary_size());
  FrameLikelihood f;
  f.delta_.resize(static_cast<std::size_t>(vocabulary_size()));
  for (int q = 0; q < vocabulary_size(); ++q) {
    const auto i = static_cast<std::size_t>(q);
    const bool z_q = present[i] != 0;
    const int parent = tree_.parent[i];
    const bool z_p = parent >= 0 && present[static_cast<std::size_t>(parent)] != 0;
    const double without = WordTerm(q, PExists(q, false), z_q, z_p);
    const double with = WordTerm(q, PExists(q, true), z_q, z_p);
    f.base_ += without;
    f.delta_[i] = with - without;
    if (options_.new_place == NewPlaceModel::kMeanField) f.new_place_ += WordTerm(q, tree_.p_z[i], z_q, z_p);
  }
  if (options_.new_place == NewPlaceModel::kSampled) {
    std::vector<double> l;
    l.reserve(samples_.size());
    for (const WordSet& s : samples_) l.push_back(f.LogLikelihood(s));
    const double max = *std::max_element(l.begin(), l.end());
    double sum = 0.0;
    for (const double x : l) sum += std::exp(x - max);
    f.new_place_ = max + std::log(sum / static_cast<double>(l.size()));
  }
  return f;
}

double FabMapModel::LogLikelihoodDirect(const WordSet& z, const WordSet& location) const {
  const std::vector<char> present = Presence(z, vocabulary_size());
  const std::vector<char> seen = Presence(location, vocabulary_size());
  double sum = 0.0;
  for (int q = 0; q < vocabulary_size(); ++q) {
    const auto i = static_cast<std::size_t>(q);
    const int parent = tree_.parent[i];
    const bool z_p = parent >= 0 && present[static_cast<std::size_t>(parent)] != 0;
    sum += WordTerm(q, PExists(q, seen[i] != 0), present[i] != 0, z_p);
  }
  return sum;
}

double FrameLikelihood::LogLikelihood(const WordSet& location) const {
  double sum = base_;
  for (const int w : location) {
    if (w < 0 || static_cast<std::size_t>(w) >= delta_.size()) {
      throw std::invalid_argument("word id " + std::to_string(w) + " outside the vocabulary");
    }
    sum += delta_[static_cast<std::size_t>(w)];
  }
  return sum;
}

}  // namespace catgraph
