// The road-free models' input slopes move one input's noise at a time, at a
// sample or at the one before: the other instant's inputs and angles are the
// same bits as before, and so is what the model computed from them. A point's
// per-instant results, kept under that key for one sample (the caller's scope).
#pragma once

#include <algorithm>
#include <cstring>

namespace pc_ekf {

// One instant's `Part`, keyed by the inputs read (at most MaxInputs) and the
// body's Angles angles since rest.
template <int MaxInputs, int Angles, class Part>
struct InstantPart {
  bool valid = false;
  double key[MaxInputs + Angles];
  Part part;
  bool same(const double* in, int count, const double (&angles)[Angles]) const {
    return valid && std::memcmp(key, in, sizeof(double) * count) == 0 &&
           std::memcmp(key + count, angles, sizeof angles) == 0;
  }
  void keep(const double* in, int count, const double (&angles)[Angles], const Part& p) {
    std::copy(in, in + count, key);
    std::copy(angles, angles + Angles, key + count);
    part = p;
    valid = true;
  }
};

// The instant of the sample and the one before.
template <int MaxInputs, int Angles, class Part>
struct OutputParts {
  int count = 0;  // the inputs read (at most MaxInputs)
  InstantPart<MaxInputs, Angles, Part> now, before;
};

}  // namespace pc_ekf
