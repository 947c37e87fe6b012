#include "pc_ekf/io/tolerances.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <stdexcept>

#include "pc_ekf/io/yaml_reader.h"

namespace pc_ekf {
namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
}  // namespace

GermSpec readGermSpec(YamlMapReader r) {
  GermSpec g;
  std::string family = "beta";
  r.text("family", family);
  try {
    g.family = germFamilyFromString(family);
  } catch (const std::invalid_argument&) {
    r.fail("family", "'" + family + "'", "beta, uniform, gaussian or gamma");
  }
  if (g.family == GermFamily::kBeta || g.family == GermFamily::kGamma) {
    r.number("alpha", g.alpha, 0.0, kInf, true);
  }
  if (g.family == GermFamily::kBeta) r.number("beta", g.beta, 0.0, kInf, true);
  r.finish();
  return g;
}

std::vector<UncertainParameter> readTolerances(YamlMapReader& root, const ModelType& type,
                                               const ModelParameters& parameters,
                                               const std::vector<UncertainParameter>& load) {
  YamlMapReader t = root.map("tolerances");
  const auto& names = type.parameterNames();
  std::set<std::string> loads;
  for (const auto& u : load) loads.insert(u.name);
  std::vector<UncertainParameter> out;
  for (std::size_t i = 0; i < names.size(); ++i) {
    const std::string& name = names[i];
    if (!t.has(name)) continue;
    if (loads.count(name)) {
      t.fail(name, "a tolerance", "no tolerance on " + name +
                                      ": it is under uncertain: (what is estimated); list it once");
    }
    UncertainParameter u;
    u.name = name;
    u.nominal = parameters.values[static_cast<Eigen::Index>(i)];
    if (t.isMap(name)) {
      YamlMapReader entry = t.map(name);
      entry.number("nominal", u.nominal, -kInf, kInf);
      entry.number("relative_range", u.relative_range, 0.0, kInf);
      u.germ = readGermSpec(entry.map("germ"));
      entry.finish();
    } else {
      t.number(name, u.relative_range, 0.0, kInf);
    }
    if (!std::isfinite(u.nominal) || u.nominal == 0.0) {
      t.fail(name, std::to_string(u.nominal),
             "a non-zero nominal value (the tolerance is relative to it)");
    }
    if (u.relative_range > 0.0) out.push_back(u);
  }
  try {
    t.finish();
  } catch (const ConfigError& e) {  // a key that is no model value: say which are
    std::string list;
    for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
    throw ConfigError(std::string(e.what()) + " (tolerances of model " + type.name() + ": " + list +
                      ")");
  }
  return out;
}

UncertainParameter momentMatched(const std::string& name, double mean, double stddev,
                                 const GermSpec& germ) {
  // mean = nominal (1 + range mu), stddev = |nominal| range sigma, range >= 0.
  const double mu = germMean(germ), sigma = germStddev(germ);
  UncertainParameter u;
  u.name = name;
  u.germ = germ;
  const double spread = stddev / sigma;  // |nominal| range
  u.nominal = mean - (mean < 0.0 ? -spread : spread) * mu;
  if (u.nominal == 0.0) throw std::invalid_argument(name + ": a zero nominal cannot carry a tolerance");
  u.relative_range = spread / std::abs(u.nominal);
  return u;
}

}  // namespace pc_ekf
