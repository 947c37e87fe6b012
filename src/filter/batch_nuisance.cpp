#include "pc_ekf/filter/batch_nuisance.h"

#include <cmath>

#include "pc_ekf/filter/trajectory_simulation.h"

namespace pc_ekf {

namespace {
constexpr double kStep = 1e-4;    // rad: the roll and cross-fall steps
constexpr double kGravity = 9.81;  // a cross-fall beta is a lateral g sin(beta)
}  // namespace

Eigen::MatrixXd nuisanceSensitivity(const MechanicalModel& model, const Eigen::VectorXd& params,
                                    const MeasurementSeries& series,
                                    const IntegratorSettings& integration,
                                    const BatchNuisance& nuisance, Eigen::VectorXd* prior_std) {
  if (!nuisance.active() || series.empty()) return {};
  const auto names = model.channelNames();
  const auto index = [&](const char* name) {
    for (std::size_t c = 0; c < names.size(); ++c) {
      if (names[c] == name) return static_cast<int>(c);
    }
    return -1;
  };
  // Columns: base, roll + step, lateral + g sin(step).
  const Eigen::MatrixXd cols = params.replicate(1, 3);
  const Eigen::VectorXd roll = (Eigen::VectorXd(3) << 0.0, kStep, 0.0).finished();
  const Eigen::VectorXd lateral =
      (Eigen::VectorXd(3) << 0.0, 0.0, kGravity * std::sin(kStep)).finished();
  std::vector<Eigen::MatrixXd> sim;
  if (!simulateChannelsWithOffsets(model, cols, sampleTimes(series), integration, roll, lateral,
                                   &sim)) {
    return {};
  }
  Eigen::Index rows = 0;
  for (const Measurement& m : series) rows += m.values.size();
  const int accel_y = index("accel_y"), accel_z = index("accel_z");
  std::vector<double> stds;
  std::vector<int> kinds;  // 0 cross-fall, 1 accel_y, 2 accel_z, 3 gyro
  if (nuisance.cross_fall > 0.0) { stds.push_back(nuisance.cross_fall); kinds.push_back(0); }
  if (nuisance.accel_bias > 0.0 && accel_y >= 0) { stds.push_back(nuisance.accel_bias); kinds.push_back(1); }
  if (nuisance.accel_bias > 0.0 && accel_z >= 0) { stds.push_back(nuisance.accel_bias); kinds.push_back(2); }
  if (nuisance.gyro_bias > 0.0) { stds.push_back(nuisance.gyro_bias); kinds.push_back(3); }
  Eigen::MatrixXd u = Eigen::MatrixXd::Zero(rows, static_cast<Eigen::Index>(kinds.size()));
  Eigen::Index row = 0;
  for (std::size_t k = 0; k < series.size(); ++k) {
    const Measurement& m = series[k];
    for (int ch : m.channels) {
      const double d_roll = (sim[k](ch, 1) - sim[k](ch, 0)) / kStep;
      const double d_cross = (sim[k](ch, 2) - sim[k](ch, 0)) / kStep;
      for (std::size_t j = 0; j < kinds.size(); ++j) {
        double v = 0.0;
        switch (kinds[j]) {
          case 0: v = d_cross; break;
          case 1: v = ch == accel_y ? 1.0 : 0.0; break;
          case 2: v = ch == accel_z ? 1.0 : 0.0; break;
          default: v = -m.time * d_roll; break;  // the roll less b t
        }
        u(row, static_cast<Eigen::Index>(j)) = v;
      }
      ++row;
    }
  }
  if (!u.allFinite()) return {};
  *prior_std = Eigen::Map<const Eigen::VectorXd>(stds.data(), static_cast<Eigen::Index>(stds.size()));
  return u;
}

NuisanceWhitening::NuisanceWhitening(const Eigen::MatrixXd& u, const Eigen::VectorXd& prior_std) {
  if (u.cols() == 0) return;
  const Eigen::MatrixXd b = u * prior_std.asDiagonal();
  // B = Q S V^T from B^T B = V S^2 V^T: Q = B V S^-1 (directions with s > 0).
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(b.transpose() * b);
  const Eigen::VectorXd s2 = eig.eigenvalues();
  const double floor = 1e-12 * std::max(1.0, s2.maxCoeff());
  std::vector<Eigen::Index> keep;
  for (Eigen::Index i = 0; i < s2.size(); ++i) {
    if (s2[i] > floor) keep.push_back(i);
  }
  q_.resize(b.rows(), static_cast<Eigen::Index>(keep.size()));
  shrink_.resize(static_cast<Eigen::Index>(keep.size()));
  for (std::size_t j = 0; j < keep.size(); ++j) {
    const Eigen::Index i = keep[j];
    const double s = std::sqrt(s2[i]);
    q_.col(static_cast<Eigen::Index>(j)) = b * eig.eigenvectors().col(i) / s;
    shrink_[static_cast<Eigen::Index>(j)] = 1.0 / std::sqrt(1.0 + s2[i]) - 1.0;
  }
}

void NuisanceWhitening::apply(Eigen::Ref<Eigen::MatrixXd> x) const {
  if (!active()) return;
  const Eigen::MatrixXd t = shrink_.asDiagonal() * (q_.transpose() * x);
  x.noalias() += q_ * t;
}

void NuisanceWhitening::apply(Eigen::Ref<Eigen::VectorXd> x) const {
  if (!active()) return;
  const Eigen::VectorXd t = shrink_.cwiseProduct(q_.transpose() * x);
  x.noalias() += q_ * t;
}

double NuisanceWhitening::absorbed() const {
  return (1.0 - (1.0 + shrink_.array()).square()).sum();
}

}  // namespace pc_ekf
