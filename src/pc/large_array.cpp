#include "pc_ekf/pc/large_array.h"

#include <sys/mman.h>

#include <new>
#include <utility>

namespace pc_ekf {

LargeArray::LargeArray(std::size_t count) : size_(count) {
  if (count == 0) return;
  constexpr std::size_t kHugePage = std::size_t(2) << 20;
  bytes_ = (count * sizeof(double) + kHugePage - 1) / kHugePage * kHugePage;
  void* p = mmap(nullptr, bytes_, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (p == MAP_FAILED) throw std::bad_alloc();
#ifdef MADV_HUGEPAGE
  madvise(p, bytes_, MADV_HUGEPAGE);  // advice only: small pages when refused
#endif
  data_ = static_cast<double*>(p);
}

LargeArray::~LargeArray() {
  if (data_) munmap(data_, bytes_);
}

LargeArray::LargeArray(LargeArray&& other) noexcept
    : data_(std::exchange(other.data_, nullptr)),
      size_(std::exchange(other.size_, 0)),
      bytes_(std::exchange(other.bytes_, 0)) {}

LargeArray& LargeArray::operator=(LargeArray&& other) noexcept {
  if (this != &other) {
    if (data_) munmap(data_, bytes_);
    data_ = std::exchange(other.data_, nullptr);
    size_ = std::exchange(other.size_, 0);
    bytes_ = std::exchange(other.bytes_, 0);
  }
  return *this;
}

}  // namespace pc_ekf
