#include "pc_ekf/pc/pdf_sampler.h"

#include <algorithm>
#include <stdexcept>

namespace pc_ekf {

ParameterPdfSampler::ParameterPdfSampler(const PolynomialBasis& basis, int parameters, int draws,
                                         int bins, std::uint64_t seed)
    : bins_(bins) {
  if (draws < 1 || bins < 1) throw std::invalid_argument("ParameterPdfSampler: draws, bins >= 1");
  for (int i = 0; i < parameters; ++i) {
    basis_at_draws_.push_back(
        basis.evaluate(sampleGerms(basis, draws, seed + static_cast<std::uint64_t>(i))));
  }
}

Histogram ParameterPdfSampler::histogram(int parameter, const Eigen::VectorXd& coefficients) const {
  const Eigen::MatrixXd& psi = basis_at_draws_.at(static_cast<std::size_t>(parameter));
  if (coefficients.size() != psi.cols()) {
    throw std::invalid_argument("ParameterPdfSampler: coefficients do not match the basis");
  }
  // As pcHistogram with lo = hi = 0: bins over the sample range.
  const Eigen::VectorXd values = psi * coefficients;
  double lo = values.minCoeff(), hi = values.maxCoeff();
  if (!(lo < hi)) {
    lo -= 0.5;
    hi += 0.5;
  }
  const double width = (hi - lo) / bins_;
  Eigen::VectorXd counts = Eigen::VectorXd::Zero(bins_);
  for (Eigen::Index i = 0; i < values.size(); ++i) {
    const double v = values(i);
    if (!(v >= lo && v <= hi)) continue;
    counts(std::min(bins_ - 1, static_cast<int>((v - lo) / width))) += 1.0;
  }
  Histogram h;
  h.edges = Eigen::VectorXd::LinSpaced(bins_ + 1, lo, hi);
  h.densities = counts / (static_cast<double>(values.size()) * width);
  return h;
}

}  // namespace pc_ekf
