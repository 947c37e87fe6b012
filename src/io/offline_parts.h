// What the offline runs (offline_estimation.cpp, offline_one_step.cpp)
// share: the summary, the final PDFs and the per-sample records' way out.
#pragma once

#include <Eigen/Dense>
#include <future>
#include <memory>
#include <string>
#include <vector>

#include "pc_ekf/filter/uncertain_parameters.h"
#include "pc_ekf/io/estimator_config.h"
#include "pc_ekf/io/offline_result.h"
#include "pc_ekf/pc/pdf_sampler.h"

namespace pc_ekf::offline {

void summarise(const EstimatorConfig& c, const Eigen::VectorXd& mean, const Eigen::VectorXd& sd,
               OfflineResult* r);

// The final PDFs (makePdfSampler: shared draws or seed + i per parameter).
// The draws do not depend on the data, so the sampler is built on a second
// thread while the filter runs (same numbers whatever the timing).
using PdfSamplerFuture = std::shared_future<std::shared_ptr<const ParameterPdfSampler>>;
PdfSamplerFuture startPdfSampler(const EstimatorConfig& c, PolynomialBasis basis);
std::vector<Histogram> pcPdfs(const PdfSamplerFuture& sampler, const Eigen::MatrixXd& coeffs);

// The rollover outputs of the final expansion (r->derived; none without
// heights or coefficients), each with its PDF from pdf's draws and bins:
// the parameters' sampler's draws when they share them (pdf.shared_draws;
// the same numbers as drawing them anew, without doing so three times).
void summariseDerived(const EstimatorConfig& c, const ParameterMapping& mapping,
                      const PolynomialBasis& basis, const Eigen::MatrixXd& coeffs,
                      const PdfSamplerFuture& sampler, OfflineResult* r);

// A record to the sink (when there is one); the result keeps the last.
void give(SampleRecord record, SampleSink* sink, OfflineResult* r);
SampleColumns columnsOf(const EstimatorConfig& c, const std::vector<std::string>& loo_channels);

}  // namespace pc_ekf::offline
