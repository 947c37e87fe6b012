// estimator_node's parameter_pdf messages off the sample callback: the
// callback hands the sample's parameter coefficients to this worker thread,
// which draws the histograms (ParameterPdfSampler, ~14 ms at n = 11 with
// 10^5 draws) and publishes them, in the order handed over. A histogram
// depends only on its coefficients, so the messages are those the callback
// would have published, later (docs/realtime.md).
#pragma once

#include <pc_ekf/ParameterPdf.h>
#include <ros/time.h>

#include <Eigen/Dense>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "pc_ekf/filter/uncertain_parameters.h"
#include "pc_ekf/io/estimator_config.h"
#include "pc_ekf/pc/pdf_sampler.h"

namespace pc_ekf {

struct PdfRequest {
  Eigen::MatrixXd coefficients;  // parameters x S
  std::uint32_t sample_index = 0;
  ros::Time stamp;
  // The derived quantities (the rollover outputs, vehicles with heights):
  // their names and expansions (names x S); empty: none.
  std::vector<std::string> derived_names;
  Eigen::MatrixXd derived;
};

// The parameter_pdf message of one sample: the parameters' histograms, then
// the derived quantities' (when the request has them and `derived_sampler`
// is given) after them, by `derived_sampler`'s draws (the parameters' own
// when they share them, pdf.shared_draws; else draws with pdf.seed, as
// estimate_offline's pdfs.csv).
ParameterPdf parameterPdf(const ParameterPdfSampler& sampler, const std::vector<std::string>& names,
                          const PdfRequest& r,
                          const ParameterPdfSampler* derived_sampler = nullptr);

// The sampler of the derived quantities' PDFs: `parameters` itself when the
// draws are shared, else one with the first seed; null when the vehicle has
// no rollover outputs.
std::shared_ptr<const ParameterPdfSampler> derivedPdfSampler(
    const EstimatorConfig& c, const ParameterMapping& mapping, const PolynomialBasis& basis,
    std::shared_ptr<const ParameterPdfSampler> parameters);

class PdfWorker {
 public:
  // `derived_sampler` (null: no derived quantities' PDFs): derivedPdfSampler's.
  PdfWorker(std::shared_ptr<const ParameterPdfSampler> sampler, std::vector<std::string> names,
            std::function<void(const ParameterPdf&)> publish,
            std::shared_ptr<const ParameterPdfSampler> derived_sampler = nullptr);
  // Drops what is still queued (shutdown), waits for the message in hand.
  ~PdfWorker();
  // Queues r; beyond kMaxQueued requests waiting, the oldest waiting one is
  // dropped (counted): when the node runs faster than PDFs are drawn, the
  // newest are published and memory stays bounded.
  void submit(PdfRequest r);
  static constexpr std::size_t kMaxQueued = 64;
  // Waits until every submitted request is published.
  void flush();
  std::size_t queued() const;
  std::uint64_t published() const;
  std::uint64_t dropped() const;

 private:
  void run();

  std::shared_ptr<const ParameterPdfSampler> sampler_, derived_sampler_;
  std::vector<std::string> names_;
  std::function<void(const ParameterPdf&)> publish_;
  mutable std::mutex mutex_;
  std::condition_variable wake_, idle_;
  std::deque<PdfRequest> queue_;  // guarded by mutex_
  bool busy_ = false, stop_ = false;
  std::uint64_t published_ = 0, dropped_ = 0;
  std::thread thread_;
};

}  // namespace pc_ekf
