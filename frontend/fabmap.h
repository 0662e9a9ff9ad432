// The FAB-MAP observation model (Cummins & Newman 2008) as CAT-Graph uses it
// (docs/catgraph-spec.md §2.4, §2.7): how likely the current frame's words
// are at a place whose node saw other words.
//
// Observations are binary bag-of-words vectors, stored as sorted lists of the
// word ids that are present. A Chow-Liu tree learned from training
// observations captures which words co-occur: every word q but the root has
// a parent p(q), with p(z_q = 1 | z_p). The detector model says how reliably
// a word that exists in the scene is seen: p(z = 1 | e = 1) and
// p(z = 1 | e = 0) (the paper's Table I: 0.39 and 0.0).
//
// For a place whose node observation is L (words Lz_q) and the current
// observation z:
//   p(e_q = 1 | L) = p(Lz_q | e=1) p(z_q=1) / Σ_s p(Lz_q | e=s) p(z_q=s)
//   log p(z | L)   = Σ_q log Σ_s p(e_q = s | L) · p(z_q | e_q = s, z_p(q))
//   p(z | e, z_p)  = β / (α + β),  α = p(z_q=z) p(z_q=¬z | e) p(z_q=¬z | z_p),
//                                  β = p(z_q=¬z) p(z_q=z | e) p(z_q=z | z_p)
// (openFABMAP's FabMap1 with the Chow-Liu tree; naive Bayes drops z_p and
// uses p(z_q | e) alone). The root word has no parent: its p(z_q | z_p) is
// its marginal p(z_q) — openFABMAP makes the root its own parent instead,
// which turns its conditional into a smoothed identity (0.99 / 0.01).
//
// Speed-up (exact): a node enters only through Lz_q ∈ {0, 1}, so a
// FrameLikelihood precomputes both per-word terms once per frame and scores a
// node in O(words in the node): log p(z | L_m) = C + Σ_{q ∈ L_m} Δ_q.
//
// Thread-compatible; a FabMapModel is immutable after construction.
#ifndef CATGRAPH_FRONTEND_FABMAP_H_
#define CATGRAPH_FRONTEND_FABMAP_H_

#include <cstdint>
#include <memory>
#include <string_view>
#include <vector>

#include "frontend/observation_model.h"

namespace catgraph {

struct ChowLiuTree {
  // Per word: parent word (-1 for the root), p(z_q = 1), p(z_q = 1 | z_p = 1),
  // p(z_q = 1 | z_p = 0), all smoothed into [0.01, 0.99] as openFABMAP does
  // (0.98 · frequency + 0.01).
  std::vector<int> parent;
  std::vector<double> p_z;
  std::vector<double> p_z_given_parent_on;
  std::vector<double> p_z_given_parent_off;
  int vocabulary_size() const { return static_cast<int>(parent.size()); }
};

// Learns the tree from training observations over `vocabulary_size` words:
// mutual information between every pair of words from their co-occurrence
// counts, the maximum spanning tree (Prim's algorithm, rooted at word 0).
// Throws std::invalid_argument on an empty training set or a word id out of
// range.
ChowLiuTree LearnChowLiuTree(const std::vector<WordSet>& training, int vocabulary_size);

// Mutual information (nats) of two binary variables from counts: n
// observations, n_a with a, n_b with b, n_ab with both.
double MutualInformation(double n, double n_a, double n_b, double n_ab);

// How likely an observation is at a place never visited (spec §2.7).
enum class NewPlaceModel {
  // FAB-MAP's mean field: p(e_q) replaced by the training marginal p(z_q).
  kMeanField,
  // openFABMAP's sampled new place: the log-mean-exp of the likelihoods
  // against sample observations of other places (the training images).
  kSampled,
};

struct FabMapOptions {
  double p_observe_given_exists = 0.39;  // p(z=1 | e=1) = 1 - p(z=0|e=1), Table I: 1 - 0.61; (0, 1]
  double p_observe_given_absent = 0.0;   // p(z=1 | e=0), Table I; [0, 1)
  bool naive_bayes = false;              // ignore the Chow-Liu tree
  NewPlaceModel new_place = NewPlaceModel::kMeanField;
  // Added to log p(z | new place) by the filter (ObservationModel::
  // NewPlaceLogOffset) [D, docs/frontend.md]: FAB-MAP's mean field scores a
  // corridor frame far below the places a few metres along the same
  // corridor, which share its far view. Nats; chosen for 500-word SIFT
  // vocabularies on rendered images (docs/frontend.md); 0 is the spec.
  double new_place_log_offset = 45.0;
};
// Throws std::invalid_argument naming the first field out of range.
void Validate(const FabMapOptions& options);

class FrameLikelihood;

class FabMapModel : public ObservationModel {
 public:
  // Throws std::invalid_argument on options out of range, an empty tree, or
  // a sampled new place without samples. `new_place_samples` (observations
  // of places other than those to be recognised) serve NewPlaceModel::kSampled.
  FabMapModel(ChowLiuTree tree, FabMapOptions options, std::vector<WordSet> new_place_samples = {});

  int vocabulary_size() const { return tree_.vocabulary_size(); }
  const ChowLiuTree& tree() const { return tree_; }
  const FabMapOptions& options() const { return options_; }

  // The per-frame tables for observation z (sorted word ids).
  FrameLikelihood ForFrame(const WordSet& z) const;

  // log p(z | L) evaluated directly, word by word (reference for tests and
  // single queries; ForFrame(z).LogLikelihood(L) gives the same value).
  double LogLikelihoodDirect(const WordSet& z, const WordSet& location) const;

  // ObservationModel: the words of z against the nodes' words.
  std::string_view Name() const override { return "fabmap"; }
  std::unique_ptr<FrameScore> ScoreFrame(const Observation& z,
                                         const std::vector<const Observation*>& places) const override;
  double NewPlaceLogOffset() const override { return options_.new_place_log_offset; }

 private:
  friend class FrameLikelihood;
  // log Σ_s p(e=s | ·) p(z_q | e=s, z_p) for word q, given p(e_q = 1).
  double WordTerm(int q, double p_exists, bool z_q, bool z_parent) const;
  double PExists(int q, bool location_has_word) const;

  ChowLiuTree tree_;
  FabMapOptions options_;
  std::vector<WordSet> samples_;
};

// log p(z | L) for one frame z against any node L, in O(|L|).
class FrameLikelihood {
 public:
  double LogLikelihood(const WordSet& location) const;
  // The new-place likelihood log p(z | z_avg) of the model's NewPlaceModel
  // (spec §2.7).
  double LogNewPlaceLikelihood() const { return new_place_; }
  // The frame's self-evidence, given its own words `z`: how much better than
  // the new place a node that saw exactly z explains it, in nats; about the
  // most any place can score (docs/frontend.md).
  double SelfEvidence(const WordSet& z) const { return LogLikelihood(z) - new_place_; }

 private:
  friend class FabMapModel;
  double base_ = 0.0;          // Σ_q term(Lz_q = 0)
  std::vector<double> delta_;  // term(Lz_q = 1) - term(Lz_q = 0)
  double new_place_ = 0.0;
};

}  // namespace catgraph

#endif  // CATGRAPH_FRONTEND_FABMAP_H_
