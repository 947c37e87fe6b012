// The node's PDF worker (estimator_run_pdfs.h): when requests come faster
// than PDFs are drawn, at most PdfWorker::kMaxQueued wait, the oldest waiting
// ones are dropped and counted, and the newest are published: memory stays
// bounded over hours at any rate.
#include <gtest/gtest.h>

#include <condition_variable>
#include <memory>
#include <mutex>
#include <vector>

#include "pc_ekf/pc/germ.h"
#include "pc_ekf/pc/pdf_sampler.h"
#include "pc_ekf/pc/polynomial_basis.h"
#include "pc_ekf/ros/estimator_run_pdfs.h"

namespace pc_ekf {
namespace {

TEST(PdfWorker, AFullQueueDropsTheOldestWaitingAndPublishesTheNewest) {
  const PolynomialBasis basis({GermSpec{GermFamily::kUniform, 0.0, 0.0}}, 1);
  const auto sampler = std::make_shared<const ParameterPdfSampler>(basis, 200, 10, 1);
  std::mutex mutex;
  std::condition_variable open_cv;
  bool open = false;
  std::vector<std::uint32_t> published;
  PdfWorker worker(sampler, {"x"}, [&](const ParameterPdf& m) {
    std::unique_lock<std::mutex> lock(mutex);
    open_cv.wait(lock, [&] { return open; });  // the first PDF holds the worker
    published.push_back(m.sample_index);
  });
  constexpr int kRequests = 200;
  for (int i = 1; i <= kRequests; ++i) {
    PdfRequest r;
    r.coefficients = (Eigen::MatrixXd(1, 2) << 1.0, 0.5).finished();
    r.sample_index = static_cast<std::uint32_t>(i);
    worker.submit(r);
    EXPECT_LE(worker.queued(), PdfWorker::kMaxQueued + 1);  // + the one being drawn
  }
  {
    std::lock_guard<std::mutex> lock(mutex);
    open = true;
  }
  open_cv.notify_all();
  worker.flush();
  const std::uint64_t dropped = worker.dropped();
  EXPECT_GE(dropped, static_cast<std::uint64_t>(kRequests) - PdfWorker::kMaxQueued - 1);
  ASSERT_EQ(published.size() + dropped, static_cast<std::size_t>(kRequests));
  // The newest are the ones published, in order.
  EXPECT_EQ(published.back(), static_cast<std::uint32_t>(kRequests));
  for (std::size_t i = 1; i < published.size(); ++i) EXPECT_LT(published[i - 1], published[i]);
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
