// Per-thread marks over the elements (faces or vertices) of a mesh, for the small local
// searches of the patch builder and the limit evaluator: a search costs O(what it touches),
// however large the mesh, with no hash map. Marks set through one Marks are reset when it ends.
#pragma once

#include <vector>

namespace subd2nurbs {

class Marks {
 public:
  /// `store` is the caller's per-thread vector (thread_local), all -1 between uses; it grows
  /// to `size` elements. One Marks per store at a time.
  Marks(std::vector<int>& store, int size) : mark_(store) {
    if (static_cast<int>(mark_.size()) < size) mark_.resize(size, -1);
  }
  Marks(const Marks&) = delete;
  Marks& operator=(const Marks&) = delete;
  ~Marks() {
    for (int i : touched_) mark_[i] = -1;
  }
  /// i's mark, -1 if none.
  int get(int i) const { return mark_[i]; }
  /// Sets i's mark (value >= 0) if it has none; false (mark unchanged) if it has one.
  bool set(int i, int value) {
    if (mark_[i] >= 0) return false;
    mark_[i] = value;
    touched_.push_back(i);
    return true;
  }
  /// Sets i's mark (value >= 0) whether or not it has one.
  void put(int i, int value) {
    if (mark_[i] < 0) touched_.push_back(i);
    mark_[i] = value;
  }

 private:
  std::vector<int>& mark_;
  std::vector<int> touched_;
};

}  // namespace subd2nurbs
