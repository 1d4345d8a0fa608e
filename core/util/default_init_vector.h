// A std::vector whose resize() leaves new elements of trivial types uninitialised.
// Used for large index arrays that are filled completely right after allocation (child
// connectivity in refinement), where zero-filling first would double the memory traffic.
#pragma once

#include <memory>
#include <vector>

namespace subd2nurbs {

template <class T, class Base = std::allocator<T>>
struct DefaultInitAllocator : Base {
  using Traits = std::allocator_traits<Base>;
  template <class U>
  struct rebind {
    using other = DefaultInitAllocator<U, typename Traits::template rebind_alloc<U>>;
  };
  using Base::Base;
  template <class U>
  void construct(U* p) noexcept(std::is_nothrow_default_constructible<U>::value) {
    ::new (static_cast<void*>(p)) U;  // default-init: no zeroing for int / double
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    Traits::construct(static_cast<Base&>(*this), p, std::forward<Args>(args)...);
  }
};

template <class T>
using DefaultInitVector = std::vector<T, DefaultInitAllocator<T>>;

}  // namespace subd2nurbs
