#include "pc_ekf/io/offline_parts.h"

#include "pc_ekf/filter/rollover_quantities.h"
#include "pc_ekf/io/estimation_setup.h"
#include "pc_ekf/pc/background_thread.h"
#include "pc_ekf/pc/in_parts.h"

namespace pc_ekf {
namespace offline {

void summarise(const EstimatorConfig& c, const Eigen::VectorXd& mean, const Eigen::VectorXd& sd,
               OfflineResult* r) {
  r->parameters.clear();
  for (std::size_t i = 0; i < c.uncertain.size(); ++i) {
    const UncertainParameter& u = c.uncertain[i];
    const double scale = u.nominal * u.relative_range;
    r->parameters.push_back({u.name, mean[i], sd[i], (mean[i] - u.nominal) / scale, sd[i] / scale});
  }
}

PdfSamplerFuture startPdfSampler(const EstimatorConfig& c, PolynomialBasis basis) {
  return std::async(std::launch::async, [&c, basis = std::move(basis)] {
    markBackgroundThread();
    return makePdfSampler(c, basis, static_cast<int>(c.uncertain.size()), machineThreads());
  });
}

std::vector<Histogram> pcPdfs(const PdfSamplerFuture& sampler, const Eigen::MatrixXd& coeffs) {
  const std::shared_ptr<const ParameterPdfSampler> s = sampler.get();  // also when not finite
  if (!coeffs.allFinite()) return {};
  return s->histograms(coeffs, machineThreads());
}

void summariseDerived(const EstimatorConfig& c, const ParameterMapping& mapping,
                      const PolynomialBasis& basis, const Eigen::MatrixXd& coeffs,
                      const PdfSamplerFuture& sampler, OfflineResult* r) {
  r->derived.clear();
  const DerivedExpansions d = rolloverExpansions(mapping, basis, coeffs, machineThreads());
  if (d.empty()) return;  // no heights: the JSON and pdfs.csv as without them
  const Eigen::VectorXd mean = pcMean(d.coefficients), sd = pcStddev(d.coefficients);
  // The parameters' draws when they share them (pdf.shared_draws), else the
  // first seed's (the first parameter's set, already drawn by the sampler).
  std::vector<Histogram> shared;
  const std::shared_ptr<const ParameterPdfSampler> s = sampler.get();
  if (s->terms() == basis.size() && s->draws() == c.pdf.draws && s->bins() == c.pdf.bins) {
    shared = s->histogramsOnFirstDraws(d.coefficients, machineThreads());
  }
  for (std::size_t i = 0; i < d.names.size(); ++i) {
    const Eigen::Index k = static_cast<Eigen::Index>(i);
    DerivedSummary s{d.names[i], mean[k], sd[k], d.coefficients.row(k).transpose(), {}};
    s.pdf = i < shared.size()
                ? shared[i]
                : pcHistogram(basis, s.coefficients, c.pdf.draws, c.pdf.bins, c.pdf.seed);
    r->derived.push_back(std::move(s));
  }
}

void give(SampleRecord record, SampleSink* sink, OfflineResult* r) {
  if (sink) sink->add(record);
  r->last_record = std::move(record);
}

SampleColumns columnsOf(const EstimatorConfig& c, const std::vector<std::string>& loo_channels) {
  SampleColumns columns;
  for (const UncertainParameter& u : c.uncertain) columns.parameters.push_back(u.name);
  columns.loo_channels = loo_channels;
  return columns;
}

}  // namespace offline

}  // namespace pc_ekf
