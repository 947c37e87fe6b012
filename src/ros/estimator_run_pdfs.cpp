#include "pc_ekf/ros/estimator_run_pdfs.h"

#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include "pc_ekf/filter/rollover_quantities.h"
#include "pc_ekf/ros/message_conversion.h"

namespace pc_ekf {

namespace {
constexpr int kNice = 10;  // the PDF worker's nice, relative to the node's
}  // namespace

ParameterPdf parameterPdf(const ParameterPdfSampler& sampler, const std::vector<std::string>& names,
                          const PdfRequest& r, const ParameterPdfSampler* derived_sampler) {
  if (!derived_sampler || r.derived_names.empty() ||
      r.derived.rows() != static_cast<Eigen::Index>(r.derived_names.size()) ||
      !r.derived.allFinite()) {
    return pdfMessage(names, sampler.histograms(r.coefficients), {}, r.sample_index, r.stamp);
  }
  // The derived quantities after the parameters (readers of the parameters alone unchanged).
  std::vector<std::string> all = names;
  all.insert(all.end(), r.derived_names.begin(), r.derived_names.end());
  std::vector<Histogram> h = sampler.histograms(r.coefficients);
  const std::vector<Histogram> d = derived_sampler->histograms(r.derived);
  h.insert(h.end(), d.begin(), d.end());
  return pdfMessage(all, h, {}, r.sample_index, r.stamp);
}

std::shared_ptr<const ParameterPdfSampler> derivedPdfSampler(
    const EstimatorConfig& c, const ParameterMapping& mapping, const PolynomialBasis& basis,
    std::shared_ptr<const ParameterPdfSampler> parameters) {
  if (!hasRolloverQuantities(mapping)) return nullptr;
  if (c.pdf.shared_draws) return parameters;
  return std::make_shared<const ParameterPdfSampler>(basis, c.pdf.draws, c.pdf.bins, c.pdf.seed);
}

PdfWorker::PdfWorker(std::shared_ptr<const ParameterPdfSampler> sampler,
                     std::vector<std::string> names,
                     std::function<void(const ParameterPdf&)> publish,
                     std::shared_ptr<const ParameterPdfSampler> derived_sampler)
    : sampler_(std::move(sampler)),
      derived_sampler_(std::move(derived_sampler)),
      names_(std::move(names)),
      publish_(std::move(publish)) {
  thread_ = std::thread([this] { run(); });
}

PdfWorker::~PdfWorker() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
    queue_.clear();
  }
  wake_.notify_all();
  thread_.join();
}

void PdfWorker::submit(PdfRequest r) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    queue_.push_back(std::move(r));
    while (queue_.size() > kMaxQueued) {
      queue_.pop_front();
      ++dropped_;
    }
  }
  wake_.notify_all();
}

void PdfWorker::flush() {
  std::unique_lock<std::mutex> lock(mutex_);
  idle_.wait(lock, [this] { return queue_.empty() && !busy_; });
}

std::size_t PdfWorker::queued() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return queue_.size() + (busy_ ? 1 : 0);
}

std::uint64_t PdfWorker::published() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return published_;
}

std::uint64_t PdfWorker::dropped() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return dropped_;
}

void PdfWorker::run() {
  // Below the filter's thread: a PDF is a view of the estimate, the
  // estimate must keep up with the samples (Linux: nice applies per thread).
  setpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)), kNice);
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    wake_.wait(lock, [this] { return stop_ || !queue_.empty(); });
    if (stop_) break;
    PdfRequest r = std::move(queue_.front());
    queue_.pop_front();
    busy_ = true;
    lock.unlock();
    const ParameterPdf msg = parameterPdf(*sampler_, names_, r, derived_sampler_.get());
    publish_(msg);  // ros::Publisher::publish is thread-safe
    lock.lock();
    busy_ = false;
    ++published_;
    if (queue_.empty()) idle_.notify_all();
  }
  busy_ = false;
  idle_.notify_all();
}

}  // namespace pc_ekf
