#include "pc_ekf/pc/germ.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace pc_ekf {

std::string toString(GermFamily family) {
  switch (family) {
    case GermFamily::kBeta:
      return "beta";
    case GermFamily::kUniform:
      return "uniform";
    case GermFamily::kGaussian:
      return "gaussian";
    case GermFamily::kGamma:
      return "gamma";
  }
  throw std::invalid_argument("toString: unknown GermFamily value");
}

GermFamily germFamilyFromString(const std::string& name) {
  if (name == "beta") return GermFamily::kBeta;
  if (name == "uniform") return GermFamily::kUniform;
  if (name == "gaussian") return GermFamily::kGaussian;
  if (name == "gamma") return GermFamily::kGamma;
  throw std::invalid_argument("unknown germ family '" + name +
                              "' (accepted: beta, uniform, gaussian, gamma)");
}

std::string describe(const GermSpec& germ) {
  std::ostringstream out;
  out << toString(germ.family);
  if (germ.family == GermFamily::kBeta) out << '(' << germ.alpha << ',' << germ.beta << ')';
  if (germ.family == GermFamily::kGamma) out << '(' << germ.alpha << ')';
  return out.str();
}

double germMean(const GermSpec& germ) {
  switch (germ.family) {
    case GermFamily::kBeta:  // x = 2u - 1, u ~ Beta(alpha, beta) on [0, 1]
      return (germ.alpha - germ.beta) / (germ.alpha + germ.beta);
    case GermFamily::kUniform:
    case GermFamily::kGaussian:
      return 0.0;
    case GermFamily::kGamma:
      return germ.alpha;
  }
  throw std::invalid_argument("germMean: unknown GermFamily value");
}

double germStddev(const GermSpec& germ) {
  switch (germ.family) {
    case GermFamily::kBeta: {
      const double s = germ.alpha + germ.beta;
      return 2.0 * std::sqrt(germ.alpha * germ.beta / (s * s * (s + 1.0)));
    }
    case GermFamily::kUniform:
      return 1.0 / std::sqrt(3.0);
    case GermFamily::kGaussian:
      return 1.0;
    case GermFamily::kGamma:
      return std::sqrt(germ.alpha);
  }
  throw std::invalid_argument("germStddev: unknown GermFamily value");
}

}  // namespace pc_ekf
