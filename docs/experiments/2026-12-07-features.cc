// Which of the local features OpenCV 4.6 on Debian offers recognise places,
// at which resolution, and at what cost: every query frame is matched against
// every reference frame by descriptors alone (Lowe's ratio test, 0.8; Hamming
// distance for binary descriptors), the reference with the most matches is
// the answer, and recall@1 is the share of queries answered with a correct
// place. No vocabulary, no filter: this measures the features, not the model.
//
//   g++ -O3 -std=c++20 -w docs/experiments/2026-12-07-features.cc -I/usr/include/opencv4 \
//       -lopencv_core -lopencv_imgcodecs -lopencv_imgproc -lopencv_features2d -o /tmp/features
//   catgraph simulate --scenario office-change -o office-change --quiet
//   OMP_NUM_THREADS=1 taskset -c 1 /tmp/features ../shared/datasets/images/corridor_vprbench office-change
//
// Dense SIFT is measured up to the native resolution only (81 ms a frame at
// 160 x 120 already).
//
// Corridor: queries query/, references ref/, correct as ground_truth.csv
// lists. Office: queries every 30th frame of traversal 2 outside the changed
// regions, references every 8th frame of traversal 1, correct within 1 m of
// the query's true position.
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace {

struct Place {
  std::string image;
  double x = 0, y = 0;
};

struct Set {
  std::string name;
  std::vector<Place> queries, references;
  std::function<bool(int, int)> correct;  // query index, reference index
};

std::vector<std::vector<std::string>> Csv(const std::string& path) {
  std::ifstream in(path);
  std::vector<std::vector<std::string>> rows;
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#') continue;
    std::vector<std::string> cells;
    std::stringstream s(line);
    for (std::string cell; std::getline(s, cell, ',');) cells.push_back(cell);
    rows.push_back(cells);
  }
  return rows;
}

Set Corridor(const std::string& dir) {
  Set set{"corridor", {}, {}, {}};
  char name[64];
  for (int i = 0; i < 111; ++i) {
    std::snprintf(name, sizeof name, "/query/%07d.jpg", i);
    set.queries.push_back({dir + name});
    std::snprintf(name, sizeof name, "/ref/%07d.jpg", i);
    set.references.push_back({dir + name});
  }
  auto truth = std::make_shared<std::vector<std::set<int>>>(111);
  for (const auto& row : Csv(dir + "/ground_truth.csv")) {
    std::stringstream s(row[1]);
    for (int j; s >> j;) (*truth)[std::stoi(row[0])].insert(j);
  }
  set.correct = [truth](int q, int r) { return (*truth)[q].contains(r); };
  return set;
}

Set Office(const std::string& dir) {
  Set set{"office-change", {}, {}, {}};
  std::vector<std::vector<double>> truth;
  bool header = true;
  for (const auto& row : Csv(dir + "/groundtruth.csv")) {
    if (header) { header = false; continue; }
    truth.push_back({std::stod(row[0]), std::stod(row[1]), std::stod(row[2])});
  }
  auto at = [&](double t) {  // linear interpolation of the true position
    std::size_t k = 1;
    while (k + 1 < truth.size() && truth[k][0] < t) ++k;
    const double a = std::clamp((t - truth[k - 1][0]) / (truth[k][0] - truth[k - 1][0]), 0.0, 1.0);
    return std::pair{truth[k - 1][1] + a * (truth[k][1] - truth[k - 1][1]),
                     truth[k - 1][2] + a * (truth[k][2] - truth[k - 1][2])};
  };
  int t1 = 0, t2 = 0;
  header = true;
  for (const auto& row : Csv(dir + "/frames.csv")) {
    if (header) { header = false; continue; }
    const auto [x, y] = at(std::stod(row[0]));
    const Place p{dir + "/" + row[1], x, y};
    if (row[2] == "1" && t1++ % 8 == 0) set.references.push_back(p);
    if (row[2] == "2" && row[3] == "0" && t2++ % 30 == 0) set.queries.push_back(p);
  }
  set.correct = [q = set.queries, r = set.references](int i, int j) {
    return std::hypot(q[i].x - r[j].x, q[i].y - r[j].y) <= 1.0;
  };
  return set;
}

struct Feature {
  std::string name;
  std::function<void(const cv::Mat&, cv::Mat&, int&)> describe;  // grey image -> descriptors, keypoints
  int norm;
};

std::vector<Feature> Features() {
  auto detector = [](cv::Ptr<cv::Feature2D> f) {
    return [f](const cv::Mat& grey, cv::Mat& d, int& n) {
      std::vector<cv::KeyPoint> k;
      f->detectAndCompute(grey, cv::noArray(), k, d);
      n = static_cast<int>(k.size());
    };
  };
  // Dense SIFT: descriptors on a grid of 24 columns (a step of width / 24,
  // at least 4 pixels), each keypoint twice the step across.
  auto dense = [](const cv::Mat& grey, cv::Mat& d, int& n) {
    static const auto sift = cv::SIFT::create();
    const float step = std::max(4.0f, grey.cols / 24.0f);
    std::vector<cv::KeyPoint> k;
    for (float y = step; y < grey.rows - step / 2; y += step) {
      for (float x = step; x < grey.cols - step / 2; x += step) k.emplace_back(x, y, 2 * step);
    }
    sift->compute(grey, k, d);
    n = static_cast<int>(k.size());
  };
  return {{"sift", detector(cv::SIFT::create()), cv::NORM_L2},
          {"dense-sift", dense, cv::NORM_L2},
          {"kaze", detector(cv::KAZE::create()), cv::NORM_L2},
          {"akaze", detector(cv::AKAZE::create()), cv::NORM_HAMMING},
          {"orb", detector(cv::ORB::create()), cv::NORM_HAMMING},
          {"brisk", detector(cv::BRISK::create()), cv::NORM_HAMMING}};
}

int Matches(const cv::Mat& a, const cv::Mat& b, int norm) {
  if (a.rows < 1 || b.rows < 2) return 0;
  std::vector<std::vector<cv::DMatch>> knn;
  cv::BFMatcher(norm).knnMatch(a, b, knn, 2);
  int good = 0;
  for (const auto& m : knn) good += m.size() == 2 && m[0].distance < 0.8f * m[1].distance;
  return good;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: %s CORRIDOR_VPRBENCH_DIR OFFICE_DATASET_DIR\n", argv[0]);
    return 2;
  }
  cv::setNumThreads(1);
  const std::vector<std::pair<Set, std::vector<double>>> sets = {{Corridor(argv[1]), {0.4, 1.0, 2.0}},
                                                                 {Office(argv[2]), {0.5, 1.0, 2.0}}};
  std::printf("| set | resolution | feature | keypoints/frame | ms/frame | recall@1 |\n|---|---|---|---|---|---|\n");
  for (const auto& [set, scales] : sets) {
    for (const double scale : scales) {
      for (const Feature& f : Features()) {
        // Dense SIFT takes 81 ms a frame at 160 x 120 already.
        if (f.name == "dense-sift" && scale > 1.0) continue;
        auto describe = [&](const std::vector<Place>& places, std::vector<cv::Mat>& out, double& ms, long& kps,
                            cv::Size& size) {
          for (const Place& p : places) {
            cv::Mat grey = cv::imread(p.image, cv::IMREAD_GRAYSCALE);
            cv::resize(grey, grey, cv::Size(), scale, scale, scale < 1 ? cv::INTER_AREA : cv::INTER_LINEAR);
            size = grey.size();
            const auto start = std::chrono::steady_clock::now();
            cv::Mat d;
            int n = 0;
            f.describe(grey, d, n);
            ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
            kps += n;
            out.push_back(d);
          }
        };
        std::vector<cv::Mat> q, r;
        double ms = 0;
        long kps = 0;
        cv::Size size;
        describe(set.queries, q, ms, kps, size);
        describe(set.references, r, ms, kps, size);
        int right = 0;
        for (std::size_t i = 0; i < q.size(); ++i) {
          int best = -1, most = 0;
          for (std::size_t j = 0; j < r.size(); ++j) {
            const int m = Matches(q[i], r[j], f.norm);
            if (m > most) most = m, best = static_cast<int>(j);
          }
          right += best >= 0 && set.correct(static_cast<int>(i), best);
        }
        const double frames = static_cast<double>(q.size() + r.size());
        std::printf("| %s | %dx%d | %s | %.0f | %.2f | %.3f (%d of %zu) |\n", set.name.c_str(), size.width,
                    size.height, f.name.c_str(), kps / frames, ms / frames, right / static_cast<double>(q.size()),
                    right, q.size());
        std::fflush(stdout);
      }
    }
  }
  return 0;
}
