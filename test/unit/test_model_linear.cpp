// Linear variant (k3 = 0, linear damper, docs/method.md §1.2) against the matrix exponential of
// its linearisation, built by hand from paper eq. 40-43 (not from the model's rhs).
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <unsupported/Eigen/MatrixFunctions>

#include "pc_ekf/model/integrator.h"
#include "pc_ekf/model/roll_plane_model.h"

namespace pc_ekf {
namespace {

VehicleParameters linearVariant(double xi1, double xi2) {
  VehicleParameters p;
  p.spring_cubic[0] = p.spring_cubic[1] = 0.0;
  p.damper = DamperLaw::kLinear;
  p.added_mass = 200.0 * (1.0 + 0.5 * xi1);
  p.added_mass_position = 0.762 * (1.0 + 0.25 * xi2);
  return p;
}

// dy/dt = A y about the equilibrium, zero road. cos(theta_s + theta) linearises to
// cos(theta_s): its derivative multiplies the static moment, which is zero.
Eigen::Matrix<double, 8, 8> systemMatrix(const VehicleParameters& p) {
  const double m = p.bar_mass, mass = p.added_mass, L = p.bar_length;
  const double D = (mass * p.added_mass_position + m * L / 2) / (m + mass);
  const double icg =
      p.bar_inertia + m * std::pow(L / 2 - D, 2) + mass * std::pow(D - p.added_mass_position, 2);
  const double cs = std::cos(solveStaticEquilibrium(p).roll_angle);
  // f_i = -k_i (x_i - xr_i) - c_i (xidot - xridot)
  Eigen::Matrix<double, 2, 8> force = Eigen::Matrix<double, 2, 8>::Zero();
  for (int i = 0; i < 2; ++i) {
    force(i, i) = -p.spring_linear[i];
    force(i, 2 + i) = p.spring_linear[i];
    force(i, 4 + i) = -p.damping[i];
    force(i, 6 + i) = p.damping[i];
  }
  // eq. 40: (m+M) [(1 - D/L) x1dd + D/L x2dd] = f1 + f2
  // eq. 41: I_cg (x2dd - x1dd) / L = cos(theta_s) (-D f1 + (L - D) f2)
  Eigen::Matrix2d lhs, rhs;
  lhs << (m + mass) * (1 - D / L), (m + mass) * D / L, -icg / L, icg / L;
  rhs << 1.0, 1.0, -D * cs, (L - D) * cs;
  Eigen::Matrix<double, 8, 8> a = Eigen::Matrix<double, 8, 8>::Zero();
  a.topRightCorner<4, 4>().setIdentity();
  a.block<2, 8>(4, 0) = lhs.partialPivLu().solve(rhs * force);
  // eq. 42-43 with y = 0: m_t xrdd = -f - k_t xr
  for (int i = 0; i < 2; ++i) {
    a.row(6 + i) = -force.row(i) / p.unsprung_mass[i];
    a(6 + i, 2 + i) -= p.tyre_stiffness[i] / p.unsprung_mass[i];
  }
  return a;
}

void expectMatchesExponential(double xi1, double xi2) {
  const VehicleParameters p = linearVariant(xi1, xi2);
  SineSettings flat;
  flat.amplitude = 0.0;
  const RollPlaneModel model(p, std::make_shared<SineRoad>(flat));
  const auto batch = model.prepare(p.toVector());
  Eigen::ArrayXXd y = batch->initialState();
  y(4, 0) = 1e-4;  // x1dot: a small push on the left body end
  const Eigen::Matrix<double, 8, 1> y0 = y.matrix();
  const Eigen::Matrix<double, 8, 8> a = systemMatrix(p);

  Eigen::Matrix<double, 8, 10> got, want;
  for (int k = 0; k < 10; ++k) {
    integrate(model, *batch, 0.3 * k, 0.3 * (k + 1), y, IntegratorSettings());
    got.col(k) = y.matrix();
    want.col(k) = (a * (0.3 * (k + 1))).exp() * y0;
  }
  for (int s = 0; s < 8; ++s) {
    const double scale = want.row(s).cwiseAbs().maxCoeff();
    ASSERT_GT(scale, 1e-9) << model.stateNames()[s];  // every state responds
    const double error = (got.row(s) - want.row(s)).cwiseAbs().maxCoeff() / scale;
    std::printf("xi (%g, %g) %-7s max %.3e, relative error %.2e\n", xi1, xi2,
                model.stateNames()[s].c_str(), scale, error);
    EXPECT_LT(error, 1e-6) << model.stateNames()[s];
  }
}

TEST(LinearVariant, MatchesMatrixExponentialAtNominal) { expectMatchesExponential(0.0, 0.0); }

TEST(LinearVariant, MatchesMatrixExponentialOffCentre) { expectMatchesExponential(1.0, 1.0); }

}  // namespace
}  // namespace pc_ekf

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
