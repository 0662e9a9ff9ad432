// A GTSAM-style factor-graph API on Ceres.
//
//   Values initial;                         // typed keys -> variables
//   initial.Insert(PoseId(0), Pose2(0, 0, 0));
//   FactorGraph graph;                      // owns its factors
//   graph.Emplace<BetweenFactor<Pose2>>(PoseId(0), PoseId(1), z, information);
//   graph.SetConstant(PoseKey(PoseId(0)));  // gauge
//   OptimizationResult result = Optimize(graph, initial);   // optimizer.h
//
// A Factor is one residual block: it names its keys and makes a Ceres cost
// function (and optionally a loss) over their parameter blocks. User-defined
// factors implement the same small interface.
//
// Parameter blocks: Pose2 [x, y, theta]; Pose3 [tx, ty, tz, qx, qy, qz, qw]
// (rotation on Ceres' EigenQuaternionManifold); switch [s].
//
// Thread-compatible.
#ifndef CATGRAPH_BACKEND_FACTOR_GRAPH_H_
#define CATGRAPH_BACKEND_FACTOR_GRAPH_H_

#include <array>
#include <compare>
#include <cstdint>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <ceres/cost_function.h>
#include <ceres/loss_function.h>

#include "backend/graph/ids.h"
#include "backend/graph/pose2.h"
#include "backend/graph/pose3.h"


namespace catgraph {

enum class KeyType { kPose, kSwitch };

// A typed variable key: poses and switches never collide.
struct Key {
  KeyType type = KeyType::kPose;
  std::int64_t id = 0;
  friend auto operator<=>(const Key&, const Key&) = default;
};
inline Key PoseKey(PoseId id) { return {KeyType::kPose, id.value()}; }
inline Key SwitchKey(SwitchId id) { return {KeyType::kSwitch, id.value()}; }
// "pose 12", "switch 3000": for error messages.
std::string ToString(Key key);

enum class VariableKind { kPose2, kPose3, kSwitch };

class Values {
 public:
  void Insert(PoseId id, const Pose2& pose);
  void Insert(PoseId id, const Pose3& pose);
  void Insert(SwitchId id, double value);

  bool Contains(Key key) const { return entries_.contains(key); }
  std::size_t size() const { return entries_.size(); }
  // Throw std::out_of_range (missing) or std::invalid_argument (other kind).
  Pose2 AtPose2(PoseId id) const;
  Pose3 AtPose3(PoseId id) const;
  double AtSwitch(SwitchId id) const;

  // The raw parameter block of `key`, for the optimizer and user factors.
  VariableKind KindOf(Key key) const;
  double* MutableBlock(Key key);
  const double* Block(Key key) const;
  static int BlockSize(VariableKind kind);
  // The size of the space the optimiser steps in (optimizer.h): a Pose3's
  // is 6, every other kind's its block size.
  static int TangentSize(VariableKind kind);
  std::vector<Key> keys() const;

 private:
  struct Entry {
    VariableKind kind = VariableKind::kPose2;
    std::array<double, 7> data{};
  };
  const Entry& Find(Key key) const;  // throws std::out_of_range
  const Entry& At(Key key, VariableKind kind) const;

  std::map<Key, Entry> entries_;  // node-based: block pointers stay valid
};

// Bounds on one coordinate of a parameter block.
struct ParameterBound {
  Key key;
  int index = 0;
  double lower = 0.0;
  double upper = 1.0;
};

class Factor {
 public:
  virtual ~Factor() = default;
  // The variables, in the order of the cost function's parameter blocks.
  virtual std::vector<Key> keys() const = 0;
  // A new cost function; ownership passes to the caller, which hands it to
  // ceres::Problem.
  virtual std::unique_ptr<ceres::CostFunction> NewCostFunction() const = 0;
  // A new robust loss, or nullptr for plain least squares.
  virtual std::unique_ptr<ceres::LossFunction> NewLossFunction() const { return nullptr; }
  // Bounds the factor needs on its variables (a linear switch lives in [0, 1]).
  virtual std::vector<ParameterBound> bounds() const { return {}; }
};

class FactorGraph {
 public:
  void Add(std::unique_ptr<Factor> factor) { factors_.push_back(std::move(factor)); }
  template <typename F, typename... Args>
  F& Emplace(Args&&... args) {
    auto factor = std::make_unique<F>(std::forward<Args>(args)...);
    F& ref = *factor;
    factors_.push_back(std::move(factor));
    return ref;
  }
  // Holds a variable fixed (gauge freedom, g2o's FIX).
  void SetConstant(Key key) { constant_.insert(key); }

  const std::vector<std::unique_ptr<Factor>>& factors() const { return factors_; }
  const std::set<Key>& constant_keys() const { return constant_; }
  std::size_t size() const { return factors_.size(); }

 private:
  std::vector<std::unique_ptr<Factor>> factors_;
  std::set<Key> constant_;
};

}  // namespace catgraph

#endif  // CATGRAPH_BACKEND_FACTOR_GRAPH_H_
