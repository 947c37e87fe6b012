// Zero-filled arrays of doubles of many megabytes (the PDF draws' basis
// values, the histograms' values): mapped directly, with transparent huge
// pages asked for, so that first touching them costs a few 2 MB page faults
// instead of thousands of 4 KB ones, and no memset (a fresh mapping is zero).
// Where the kernel gives no huge pages it is an ordinary zeroed allocation.
#pragma once

#include <cstddef>

namespace pc_ekf {

class LargeArray {
 public:
  LargeArray() = default;
  explicit LargeArray(std::size_t count);  // throws std::bad_alloc
  ~LargeArray();
  LargeArray(LargeArray&& other) noexcept;
  LargeArray& operator=(LargeArray&& other) noexcept;
  LargeArray(const LargeArray&) = delete;
  LargeArray& operator=(const LargeArray&) = delete;

  double* data() { return data_; }
  const double* data() const { return data_; }
  std::size_t size() const { return size_; }
  double& operator[](std::size_t i) { return data_[i]; }
  const double& operator[](std::size_t i) const { return data_[i]; }

 private:
  double* data_ = nullptr;
  std::size_t size_ = 0;
  std::size_t bytes_ = 0;  // mapped
};

}  // namespace pc_ekf
