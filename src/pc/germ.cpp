#include "pc_ekf/pc/germ.h"

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

}  // namespace pc_ekf
