// SmallVector<T, N>: a vector that keeps up to N elements inside itself and goes to the heap
// only beyond that.
//
// Why: a regular patch is 16 poles on two knot vectors {0, 1} x {4, 4}, and a boundary curve
// between two regular patches is 4 poles used twice. Stored in std::vector, each of those
// small arrays is a heap block of its own, about twenty per coarse quad, and allocating and
// freeing them was over half of building a mostly regular cage's patches (docs/benchmarks.md).
// Inline, a regular quad's patch and curves need none.
//
// It has the part of std::vector's interface the patch code uses, with the same meaning. T
// must be trivially copyable (points, numbers, plain index records), so elements are copied
// as bytes and never destroyed one by one.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdlib>
#include <cstring>
#include <initializer_list>
#include <iterator>
#include <new>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace subd2nurbs {

template <class T, std::size_t N>
class SmallVector {
  static_assert(std::is_trivially_copyable_v<T>, "SmallVector copies its elements as bytes");
  static_assert(N > 0, "SmallVector needs room for one element inline");

 public:
  using value_type = T;
  using size_type = std::size_t;
  using iterator = T*;
  using const_iterator = const T*;
  using reference = T&;
  using const_reference = const T&;

  SmallVector() noexcept {}  // user-provided: the inline room is left uninitialised, not zeroed
  SmallVector(std::initializer_list<T> values) { assign(values.begin(), values.end()); }
  explicit SmallVector(size_type n, const T& value = T()) { assign(n, value); }
  template <class It, class = typename std::iterator_traits<It>::iterator_category>
  SmallVector(It first, It last) { assign(first, last); }
  SmallVector(const std::vector<T>& values) { assign(values.begin(), values.end()); }
  SmallVector(const SmallVector& other) { assign(other.begin(), other.end()); }
  SmallVector(SmallVector&& other) noexcept { take(other); }
  SmallVector& operator=(const SmallVector& other) {
    if (this != &other) assign(other.begin(), other.end());
    return *this;
  }
  SmallVector& operator=(SmallVector&& other) noexcept {
    if (this != &other) {
      release();
      take(other);
    }
    return *this;
  }
  SmallVector& operator=(std::initializer_list<T> values) {
    assign(values.begin(), values.end());
    return *this;
  }
  ~SmallVector() { release(); }

  size_type size() const { return size_; }
  bool empty() const { return size_ == 0; }
  size_type capacity() const { return capacity_; }
  T* data() { return data_; }
  const T* data() const { return data_; }
  T& operator[](size_type i) { return data_[i]; }
  const T& operator[](size_type i) const { return data_[i]; }
  T& at(size_type i) { return data_[checked(i)]; }
  const T& at(size_type i) const { return data_[checked(i)]; }
  T* begin() { return data_; }
  T* end() { return data_ + size_; }
  const T* begin() const { return data_; }
  const T* end() const { return data_ + size_; }
  const T* cbegin() const { return data_; }
  const T* cend() const { return data_ + size_; }
  T& front() { return data_[0]; }
  const T& front() const { return data_[0]; }
  T& back() { return data_[size_ - 1]; }
  const T& back() const { return data_[size_ - 1]; }

  void reserve(size_type n) {
    if (n <= capacity_) return;
    T* grown = static_cast<T*>(std::malloc(n * sizeof(T)));
    if (!grown) throw std::bad_alloc();
    if (size_) std::memcpy(static_cast<void*>(grown), data_, size_ * sizeof(T));
    if (data_ != inline_data()) std::free(data_);
    data_ = grown;
    capacity_ = n;
  }
  void clear() { size_ = 0; }
  void resize(size_type n, const T& value = T()) {
    const T copy = value;  // value may live in this vector
    reserve(n);
    for (size_type i = size_; i < n; ++i) new (data_ + i) T(copy);
    size_ = n;
  }
  void assign(size_type n, const T& value) {
    size_ = 0;
    resize(n, value);
  }
  template <class It>
  void assign(It first, It last) {
    size_ = 0;
    if constexpr (std::is_base_of_v<std::forward_iterator_tag, typename std::iterator_traits<It>::iterator_category>)
      reserve(static_cast<size_type>(std::distance(first, last)));
    for (; first != last; ++first) push_back(*first);
  }
  void push_back(const T& value) {
    if (size_ == capacity_) {
      const T copy = value;  // value may live in this vector
      reserve(2 * capacity_);
      new (data_ + size_++) T(copy);
      return;
    }
    new (data_ + size_++) T(value);
  }
  template <class... Args>
  T& emplace_back(Args&&... args) {
    push_back(T{std::forward<Args>(args)...});
    return back();
  }
  void pop_back() { --size_; }
  T* insert(const T* pos, const T& value) {
    const size_type at = static_cast<size_type>(pos - data_);
    const T copy = value;
    if (size_ == capacity_) reserve(2 * capacity_);
    std::memmove(static_cast<void*>(data_ + at + 1), data_ + at, (size_ - at) * sizeof(T));
    new (data_ + at) T(copy);
    ++size_;
    return data_ + at;
  }
  template <class It, class = typename std::iterator_traits<It>::iterator_category>
  T* insert(const T* pos, It first, It last) {
    const size_type at = static_cast<size_type>(pos - data_);
    const std::vector<T> added(first, last);  // the range may live in this vector
    if (size_ + added.size() > capacity_) reserve(std::max(size_ + added.size(), 2 * capacity_));
    std::memmove(static_cast<void*>(data_ + at + added.size()), data_ + at, (size_ - at) * sizeof(T));
    if (!added.empty()) std::memcpy(static_cast<void*>(data_ + at), added.data(), added.size() * sizeof(T));
    size_ += added.size();
    return data_ + at;
  }
  T* erase(const T* pos) { return erase(pos, pos + 1); }
  T* erase(const T* first, const T* last) {
    const size_type at = static_cast<size_type>(first - data_), n = static_cast<size_type>(last - first);
    std::memmove(static_cast<void*>(data_ + at), data_ + at + n, (size_ - at - n) * sizeof(T));
    size_ -= n;
    return data_ + at;
  }

  friend bool operator==(const SmallVector& a, const SmallVector& b) {
    return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin());
  }
  friend bool operator!=(const SmallVector& a, const SmallVector& b) { return !(a == b); }

 private:
  size_type checked(size_type i) const {
    if (i >= size_) throw std::out_of_range("SmallVector::at: index " + std::to_string(i) + " of " + std::to_string(size_));
    return i;
  }
  void release() {
    if (data_ != inline_data()) std::free(data_);
    data_ = inline_data();
    size_ = 0;
    capacity_ = N;
  }
  // Takes other's elements and leaves it empty (inline elements are copied).
  void take(SmallVector& other) {
    if (other.data_ == other.inline_data()) {
      std::memcpy(static_cast<void*>(inline_data()), other.inline_data(), other.size_ * sizeof(T));
      data_ = inline_data();
      capacity_ = N;
    } else {
      data_ = other.data_;
      capacity_ = other.capacity_;
      other.data_ = other.inline_data();
      other.capacity_ = N;
    }
    size_ = other.size_;
    other.size_ = 0;
  }

  T* inline_data() { return reinterpret_cast<T*>(room_); }
  const T* inline_data() const { return reinterpret_cast<const T*>(room_); }

  // Raw bytes, so that an empty SmallVector constructs no element (T's default constructor may
  // zero a whole Bezier net); elements are created by copy where they are added.
  alignas(T) unsigned char room_[N * sizeof(T)];
  T* data_ = inline_data();
  size_type size_ = 0;
  size_type capacity_ = N;
};

}  // namespace subd2nurbs
