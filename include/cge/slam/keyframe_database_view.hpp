#pragma once
// KeyframeDatabaseView: read access to the keyframes of a map and their covisibility, which is all
// the loop closer (and a host system plugging its own map into it) needs. The reference pipeline's
// map implements it; tests implement it over a plain vector.
//
// Contract: ids are 0 .. keyframe_count() - 1; keyframe(id) stays valid until the map changes;
// covisible_keyframes(id, n) lists the other keyframes that share at least one map point with `id`,
// most shared points first, ties broken by the smaller id (so the order is deterministic), at most
// n of them (all when n < 0).
#include <vector>

#include "cge/slam/keyframe.hpp"

namespace cge {
namespace slam {

class KeyframeDatabaseView {
 public:
  virtual ~KeyframeDatabaseView() = default;
  virtual int keyframe_count() const = 0;
  virtual const Keyframe& keyframe(int id) const = 0;
  virtual std::vector<int> covisible_keyframes(int id, int max_count) const = 0;

 protected:
  KeyframeDatabaseView() = default;
  KeyframeDatabaseView(const KeyframeDatabaseView&) = default;
  KeyframeDatabaseView& operator=(const KeyframeDatabaseView&) = default;
};

}  // namespace slam
}  // namespace cge
