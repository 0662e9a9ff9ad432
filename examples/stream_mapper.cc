// Streams a dataset through catgraph's online Mapper frame by frame, as a
// robot would feed it, and prints each loop closure as it is made and what
// the corrected map's error is after it.
//
//   catgraph simulate --scenario office-change -o office   # or your own data
//   stream_mapper office
#include <cstdio>
#include <exception>

#include <catgraph/backend/evaluation.h>
#include <catgraph/frontend/fabmap.h>
#include <catgraph/mapping/mapper.h>

int main(int argc, char** argv) {
  using namespace catgraph;
  if (argc != 2) return std::fprintf(stderr, "usage: %s DATASET\n", argv[0]), 2;
  try {
    const Dataset data = ReadDataset(argv[1]);
    // A robot carries its vocabulary; here it is trained on the first traversal.
    const Vocabulary vocabulary = TrainMapVocabulary(data, {}).vocabulary;
    const FabMapModel model(vocabulary.tree(), FabMapOptions{});
    mapping::Mapper mapper(model, {});
    const std::vector<Pose2> odometry = PosesAtFrames(data, data.odometry);
    const Trajectory2 truth = mapping::TruthAtFrames(data);
    for (std::size_t k = 0; k < data.frames.size(); ++k) {
      const Observation z{vocabulary.Words(ReadImage(data.ImagePath(k))), {}};
      const mapping::FrameResult r = mapper.AddFrame({data.frames[k].timestamp_s, odometry[k]}, z);
      for (const LoopClosure& c : r.closures) {
        std::printf("frame %4zu: %-8s closure %4d -> %4d\n", k, c.kind == ClosureKind::kVisual ? "visual" : "inferred",
                    c.frame, c.matched_frame);
      }
      if (r.solve && !truth.empty()) {
        std::printf("frame %4zu: map re-solved in %.0f ms, %d closures accepted, ATE %.3f m\n", k,
                    1e3 * r.solve->time_s, r.solve->accepted, EvaluateTrajectory(mapper.Map(), truth).ate_m.rmse);
      }
    }
    std::printf("%zu frames, %zu closures\n", data.frames.size(), mapper.front_end().closures.size());
  } catch (const std::exception& e) {
    return std::fprintf(stderr, "error: %s\n", e.what()), 1;
  }
  return 0;
}
