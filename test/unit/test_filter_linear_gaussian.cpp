// docs/method.md §7: on a linear-Gaussian problem the square-root one-step filter, the
// square-root whole-set update and square-root ES-MDA equal the textbook
// Kalman filter; the paper rule keeps the Kalman mean update but its
// covariance is (I-KH)P(I-KH)^T.
#include <gtest/gtest.h>

#include <memory>
#include <random>
#include <unsupported/Eigen/MatrixFunctions>

#include "pc_ekf/filter/batch_update.h"
#include "pc_ekf/filter/one_step_filter.h"
#include "pc_ekf/filter/posterior_residual.h"
#include "linear_forced_model.h"
#include "pc_ekf/pc/pc_statistics.h"

namespace pc_ekf {
namespace {

using testing::LinearForcedModel;

constexpr int kSamples = 50;
constexpr double kDt = 0.1;

struct Problem {
  std::shared_ptr<LinearForcedModel> model;
  std::shared_ptr<PcPropagator> propagator;
  MeasurementSeries data;
  NoiseModel noise{0.05, 1e-6};
};

Problem makeProblem() {
  Problem p;
  Eigen::MatrixXd a(2, 2), b(2, 2), c(2, 2);
  a << 0.0, 1.0, -4.0, -0.4;  // damped oscillator
  b << 0.0, 0.3, 1.0, -0.5;
  c << 1.0, 0.0, 0.0, 1.0;
  p.model = std::make_shared<LinearForcedModel>(a, b, c, Eigen::Vector2d(1.0, 2.0));
  std::vector<UncertainParameter> u(2);
  u[0] = {"theta0", 1.0, 0.3, GermSpec{GermFamily::kGaussian, 2.0, 2.0}};
  u[1] = {"theta1", 2.0, 0.2, GermSpec{GermFamily::kGaussian, 2.0, 2.0}};
  const PolynomialBasis basis(ParameterMapping(*p.model, u).germs(), 1);
  const CollocationDesign design(basis, PointSequence::kHalton, 8);
  p.propagator = std::make_shared<PcPropagator>(p.model, basis, design, ParameterMapping(*p.model, u),
                                                IntegratorSettings{0.01});
  // Data from theta = (1.2, 1.7), 5 % noise, channel subsets vary per sample.
  std::mt19937_64 rng(42);
  std::normal_distribution<double> n;
  const Eigen::Matrix<double, 2, 1> truth(1.2, 1.7);
  Eigen::Vector2d y = Eigen::Vector2d::Zero();
  const Eigen::MatrixXd phi = (a * kDt).exp();  // data need not use the filter's integrator
  const Eigen::MatrixXd gam = a.inverse() * (phi - Eigen::MatrixXd::Identity(2, 2)) * b;
  for (int k = 1; k <= kSamples; ++k) {
    y = phi * y + gam * truth;
    Measurement m;
    m.time = k * kDt;
    m.channels = k % 3 == 0 ? std::vector<int>{1} : std::vector<int>{0, 1};
    m.values.resize(m.channels.size());
    for (std::size_t i = 0; i < m.channels.size(); ++i) {
      m.values[i] = y[m.channels[i]] * (1.0 + 0.05 * n(rng)) + 1e-3 * n(rng);
    }
    p.data.push_back(m);
  }
  return p;
}

// The filter's own discrete dynamics of [y; theta]: RK4 is affine, so its
// map over one interval is found by propagating unit vectors.
Eigen::MatrixXd transitionMatrix(const Problem& p) {
  Eigen::MatrixXd phi = Eigen::MatrixXd::Identity(4, 4);
  Eigen::MatrixXd params(2, 4);
  params << 0, 0, 1, 0, 0, 0, 0, 1;
  Eigen::ArrayXXd y = Eigen::ArrayXXd::Zero(2, 4);
  y(0, 0) = 1.0;
  y(1, 1) = 1.0;
  const auto batch = p.model->prepare(params);
  integrate(*p.model, *batch, 0.0, kDt, y, p.propagator->integration());
  phi.topRows(2) = y.matrix();
  return phi;
}

struct Gaussian {
  Eigen::VectorXd mean;
  Eigen::MatrixXd cov;
};

Gaussian priorOf(const Problem& p) {
  const Eigen::MatrixXd x = p.propagator->priorState();
  return {x.col(0), pcCovariance(x)};
}

Eigen::MatrixXd observationRows(const Measurement& m) {
  Eigen::MatrixXd h = Eigen::MatrixXd::Zero(m.channels.size(), 4);
  for (std::size_t i = 0; i < m.channels.size(); ++i) h(i, m.channels[i]) = 1.0;
  return h;
}

// Textbook predict + update of [y; theta].
void kalmanStep(const Eigen::MatrixXd& phi, const Measurement& m, const NoiseModel& noise,
                Gaussian* kf) {
  kf->mean = phi * kf->mean;
  kf->cov = phi * kf->cov * phi.transpose();
  const Eigen::MatrixXd h = observationRows(m);
  // R in full: the sensor's diagonal and, off it, what the readings share.
  Eigen::MatrixXd r = noise.variances(m).asDiagonal();
  if (m.extra_covariance.size() != 0) {
    r += m.extra_covariance;
    r.diagonal() = noise.variances(m);
  }
  const Eigen::MatrixXd s = h * kf->cov * h.transpose() + r;
  const Eigen::MatrixXd k = kf->cov * h.transpose() * s.inverse();
  kf->mean += k * (m.values - h * kf->mean);
  kf->cov = (Eigen::MatrixXd::Identity(4, 4) - k * h) * kf->cov;
}

double maxDiff(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return (a - b).cwiseAbs().maxCoeff();
}

TEST(LinearGaussian, SquareRootOneStepEqualsTheTextbookKalmanFilter) {
  const Problem p = makeProblem();
  const Eigen::MatrixXd phi = transitionMatrix(p);
  Gaussian kf = priorOf(p);
  OneStepSettings settings;
  settings.noise = p.noise;
  OneStepFilter filter(p.propagator, settings);
  double worst_mean = 0.0, worst_cov = 0.0;
  for (const Measurement& m : p.data) {
    kalmanStep(phi, m, p.noise, &kf);
    filter.process(m);
    worst_mean = std::max(worst_mean, maxDiff(filter.state().col(0), kf.mean) / kf.mean.norm());
    worst_cov = std::max(worst_cov, maxDiff(pcCovariance(filter.state()), kf.cov) / kf.cov.norm());
  }
  EXPECT_LT(worst_mean, 1e-10);
  EXPECT_LT(worst_cov, 1e-10);
  // The data must have moved the estimate: theta1 prior std 0.4 -> far smaller.
  EXPECT_LT(std::sqrt(kf.cov(3, 3)), 0.1);
}

TEST(LinearGaussian, PaperRuleKeepsTheMeanUpdateWithJosephCovariance) {
  const Problem p = makeProblem();
  OneStepSettings settings;
  settings.noise = p.noise;
  settings.rule = UpdateRule::kPaper;
  OneStepFilter filter(p.propagator, settings);
  Eigen::MatrixXd x = filter.state();
  double worst_mean = 0.0, worst_cov = 0.0, removed_extra = 0.0;
  double t = 0.0;
  for (const Measurement& m : p.data) {
    p.propagator->forecast(x, t, m.time);  // same forecast as inside the filter
    t = m.time;
    const Eigen::MatrixXd cov = pcCovariance(x);
    const Eigen::MatrixXd h = observationRows(m);
    const Eigen::MatrixXd r = p.noise.variances(m).asDiagonal();
    const Eigen::MatrixXd k = cov * h.transpose() * (h * cov * h.transpose() + r).inverse();
    const Eigen::MatrixXd ikh = Eigen::MatrixXd::Identity(4, 4) - k * h;
    const Eigen::VectorXd mean = x.col(0) + k * (m.values - h * x.col(0));
    filter.process(m);
    x = filter.state();
    worst_mean = std::max(worst_mean, maxDiff(x.col(0), mean) / mean.norm());
    worst_cov = std::max(worst_cov,
                         maxDiff(pcCovariance(x), ikh * cov * ikh.transpose()) / cov.norm());
    removed_extra = std::max(removed_extra, (ikh * cov - pcCovariance(x)).trace());
  }
  EXPECT_LT(worst_mean, 1e-10);
  EXPECT_LT(worst_cov, 1e-10);
  EXPECT_GT(removed_extra, 0.0);  // K R K^T is really removed
}

// Errors in variables: the two channels' noise correlated (rho -0.6) through
// a shared part, as when both are predicted from the same noisy inputs.
Problem withCorrelatedNoise() {
  Problem p = makeProblem();
  for (Measurement& m : p.data) {
    m.extra_covariance = Eigen::MatrixXd::Zero(m.values.size(), m.values.size());
    if (m.values.size() != 2) continue;
    const Eigen::Vector2d sd = p.noise.variances(m).cwiseSqrt();
    m.extra_covariance << 0.3 * sd[0] * sd[0], -0.6 * sd[0] * sd[1] * 1.3, -0.6 * sd[0] * sd[1] * 1.3,
        0.3 * sd[1] * sd[1];
  }
  return p;
}

TEST(LinearGaussian, CorrelatedNoiseEveryFilterEqualsTheFullRKalmanFilter) {
  const Problem p = withCorrelatedNoise();
  ASSERT_TRUE(NoiseWhitening(p.noise, p.data[0]).active());
  ASSERT_FALSE(NoiseWhitening(p.noise, p.data[2]).active());  // one channel
  const Eigen::MatrixXd phi = transitionMatrix(p);
  Gaussian kf = priorOf(p), diagonal = priorOf(p);
  OneStepSettings settings;
  settings.noise = p.noise;
  OneStepFilter filter(p.propagator, settings);
  double worst_mean = 0.0, worst_cov = 0.0, nis_diff = 0.0;
  for (const Measurement& m : p.data) {
    const Eigen::MatrixXd predicted = phi * kf.cov * phi.transpose();
    const Eigen::VectorXd innovation = m.values - observationRows(m) * phi * kf.mean;
    kalmanStep(phi, m, p.noise, &kf);
    Measurement without = m;
    without.extra_covariance = m.extra_covariance.diagonal().asDiagonal();
    kalmanStep(phi, without, p.noise, &diagonal);
    const StepResult r = filter.process(m);
    Eigen::MatrixXd rr = p.noise.variances(m).asDiagonal();
    rr += m.extra_covariance;
    rr.diagonal() = p.noise.variances(m);
    const Eigen::MatrixXd h = observationRows(m);
    const double nis = innovation.dot((h * predicted * h.transpose() + rr).ldlt().solve(innovation));
    nis_diff = std::max(nis_diff, std::abs(r.update.nis - nis) / nis);
    worst_mean = std::max(worst_mean, maxDiff(filter.state().col(0), kf.mean) / kf.mean.norm());
    worst_cov = std::max(worst_cov, maxDiff(pcCovariance(filter.state()), kf.cov) / kf.cov.norm());
  }
  EXPECT_LT(worst_mean, 1e-10);
  EXPECT_LT(worst_cov, 1e-10);
  EXPECT_LT(nis_diff, 1e-9);
  // The correlation matters: the diagonal R's answer is another one.
  EXPECT_GT(maxDiff(diagonal.cov, kf.cov) / kf.cov.norm(), 1e-3);

  const Gaussian ref{kf.mean.tail(2), kf.cov.bottomRightCorner(2, 2)};
  const BatchResult whole = batchUpdate(*p.propagator, p.data, p.noise, UpdateRule::kSquareRoot, {1.0});
  const BatchResult esmda =
      batchUpdate(*p.propagator, p.data, p.noise, UpdateRule::kSquareRoot, {4.0, 4.0, 4.0, 4.0});
  for (const BatchResult* b : {&whole, &esmda}) {
    EXPECT_LT(maxDiff(b->mean, ref.mean) / ref.mean.norm(), 1e-10);
    EXPECT_LT(maxDiff(pcCovariance(b->coefficients), ref.cov) / ref.cov.norm(), 1e-10);
  }
}

// The likelihood's residuals (the reference posterior, the predictive check)
// whitened by the full R: |r|^2 = e' R^-1 e.
TEST(LinearGaussian, WhitenedResidualsTakeTheFullR) {
  const Problem p = withCorrelatedNoise();
  std::vector<Eigen::MatrixXd> channels;
  double expected = 0.0;
  for (const Measurement& m : p.data) {
    Eigen::MatrixXd c(2, 1);
    c << 0.9 * m.values[0], 1.1 * m.values[m.values.size() - 1];
    channels.push_back(c);
    Eigen::VectorXd e(m.values.size());
    for (Eigen::Index i = 0; i < e.size(); ++i) e[i] = m.values[i] - c(m.channels[i], 0);
    Eigen::MatrixXd rr = p.noise.variances(m).asDiagonal();
    rr += m.extra_covariance;
    rr.diagonal() = p.noise.variances(m);
    expected += e.dot(rr.ldlt().solve(e));
  }
  const Eigen::MatrixXd r = whitenedResiduals(p.data, p.noise, channels);
  EXPECT_NEAR(r.squaredNorm(), expected, 1e-10 * expected);
}

// Batch posterior of theta: the sequential KF's final theta block.
Gaussian batchPosterior(const Problem& p) {
  const Eigen::MatrixXd phi = transitionMatrix(p);
  Gaussian kf = priorOf(p);
  for (const Measurement& m : p.data) {
    kalmanStep(phi, m, p.noise, &kf);
  }
  return {kf.mean.tail(2), kf.cov.bottomRightCorner(2, 2)};
}

TEST(LinearGaussian, SquareRootWholeSetAndEsMdaEqualTheBatchKalmanFilter) {
  const Problem p = makeProblem();
  const Gaussian ref = batchPosterior(p);
  const BatchResult whole = batchUpdate(*p.propagator, p.data, p.noise, UpdateRule::kSquareRoot, {1.0});
  const BatchResult esmda =
      batchUpdate(*p.propagator, p.data, p.noise, UpdateRule::kSquareRoot, {4.0, 4.0, 4.0, 4.0});
  EXPECT_EQ(whole.observations, 84);  // 50 samples, every third with one channel
  EXPECT_EQ(esmda.iterations, 4);
  for (const BatchResult* b : {&whole, &esmda}) {
    EXPECT_LT(maxDiff(b->mean, ref.mean) / ref.mean.norm(), 1e-10);
    EXPECT_LT(maxDiff(pcCovariance(b->coefficients), ref.cov) / ref.cov.norm(), 1e-10);
  }
}

TEST(LinearGaussian, PaperWholeSetKeepsTheMeanButShrinksTheCovariance) {
  const Problem p = makeProblem();
  const Gaussian ref = batchPosterior(p);
  const BatchResult paper = batchUpdate(*p.propagator, p.data, p.noise, UpdateRule::kPaper, {1.0});
  EXPECT_LT(maxDiff(paper.mean, ref.mean) / ref.mean.norm(), 1e-10);
  EXPECT_LT(pcCovariance(paper.coefficients).trace(), ref.cov.trace());
}

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
