#include "backend/factor_graph.h"

#include <stdexcept>
#include <string>

namespace catgraph {
std::string ToString(Key key) {
  return std::string(key.type == KeyType::kPose ? "pose " : "switch ") + std::to_string(key.id);
}

void Values::Insert(PoseId id, const Pose2& pose) {
  Entry e{VariableKind::kPose2, {pose.x(), pose.y(), pose.theta()}};
  entries_.insert_or_assign(PoseKey(id), e);
}

void Values::Insert(PoseId id, const Pose3& pose) {
  const auto& t = pose.translation();
  const auto& q = pose.rotation();
  Entry e{VariableKind::kPose3, {t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w()}};
  entries_.insert_or_assign(PoseKey(id), e);
}

void Values::Insert(SwitchId id, double value) {
  entries_.insert_or_assign(SwitchKey(id), Entry{VariableKind::kSwitch, {value}});
}

const Values::Entry& Values::Find(Key key) const {
  auto it = entries_.find(key);
  if (it == entries_.end()) throw std::out_of_range("Values: no variable for " + ToString(key));
  return it->second;
}

const Values::Entry& Values::At(Key key, VariableKind kind) const {
  const Entry& entry = Find(key);
  if (entry.kind != kind) {
    throw std::invalid_argument("Values: " + ToString(key) + " holds another kind of variable");
  }
  return entry;
}

Pose2 Values::AtPose2(PoseId id) const {
  const auto& d = At(PoseKey(id), VariableKind::kPose2).data;
  return {d[0], d[1], d[2]};
}

Pose3 Values::AtPose3(PoseId id) const {
  const auto& d = At(PoseKey(id), VariableKind::kPose3).data;
  return {Eigen::Vector3d(d[0], d[1], d[2]), Eigen::Quaterniond(d[6], d[3], d[4], d[5])};
}

double Values::AtSwitch(SwitchId id) const {
  return At(SwitchKey(id), VariableKind::kSwitch).data[0];
}

VariableKind Values::KindOf(Key key) const { return Find(key).kind; }

const double* Values::Block(Key key) const { return Find(key).data.data(); }

// The entry is ours and non-const here; only the lookup is shared.
double* Values::MutableBlock(Key key) { return const_cast<double*>(Block(key)); }

int Values::BlockSize(VariableKind kind) {
  switch (kind) {
    case VariableKind::kPose2: return 3;
    case VariableKind::kPose3: return 7;
    case VariableKind::kSwitch: return 1;
  }
  return 0;
}

int Values::TangentSize(VariableKind kind) { return kind == VariableKind::kPose3 ? 6 : BlockSize(kind); }

std::vector<Key> Values::keys() const {
  std::vector<Key> keys;
  keys.reserve(entries_.size());
  for (const auto& [key, entry] : entries_) keys.push_back(key);
  return keys;
}

}  // namespace catgraph
