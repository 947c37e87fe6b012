// What keeps the one-step and batch updates honest on data the model did not
// generate (docs/method.md §5.6-5.8): the physical-domain rule (damp an update
// whose parameter means would leave the prior support), parameter drift (a
// random walk folded into the PC coefficients) and re-opening the uncertainty
// after a persistent health violation. See docs/reliability.md, "Safeguards".
#pragma once

#include <Eigen/Dense>
#include <string>

#include "pc_ekf/pc/setting_breach.h"


namespace pc_ekf {

// ignore: the paper's behaviour (means may leave the support, flagged only by
// the PDF-mass warning); damp: scale the whole update by the largest factor
// in [0, 1] that keeps every parameter mean inside its support.
enum class SupportRule { kIgnore, kDamp };
std::string toString(SupportRule r);
SupportRule supportRuleFromString(const std::string& s);  // throws std::invalid_argument

// kLoad: the load's parameters (added_mass...) back to their prior, the
// vehicle values kept (filter.linearization: mean only).
enum class ReopenMode { kOff, kWidth, kPrior, kLoad };
std::string toString(ReopenMode m);
ReopenMode reopenModeFromString(const std::string& s);  // throws std::invalid_argument

struct ReopenSettings {
  ReopenMode mode = ReopenMode::kOff;
  double width = 0.5;  // kWidth: std after re-opening, as a fraction of the prior std
  int after = 3;       // consecutive samples with the windowed NIS outside its bounds
};

// Re-linearisation (docs/method.md §4.9): the first samples are assimilated
// while the distribution is as wide as the prior, and a linear update over
// that width leaves an error the later samples do not remove. When a
// parameter's std has shrunk below `shrink` x its std at the start, the
// filter starts again from a working prior in the same germs (for that
// parameter: mean = the current mean, std = `width` x the current std, inside
// the prior's support; the others as they started) and re-runs the samples
// kept since the start. Off when shrink = 0.
struct RelinearizeSettings {
  double shrink = 0.0;
  double width = 20.0;
  int max_restarts = 4;
  int max_samples = 5000;  // samples kept for a re-run; more end re-linearisation
  // Deferral (docs/realtime.md): a re-run due after sample k runs on a worker
  // thread while the filter goes on, and its state replaces the filter's after
  // sample k + ceil(defer x k). 0 = re-run within sample k.
  double defer = 0.0;
  // The working prior is centred by the data, and it stands in for the prior
  // in the directions it narrows. true: what the filter reports has the
  // working prior's information replaced by the prior's (information form,
  // Gaussian in the parameters; prior_correction.h), so the working prior may
  // be narrow (a local linearisation) without counting the data twice and
  // without losing what only the prior says (a ridge the readings leave open).
  bool prior_correction = false;
};
// Its rules: 0 <= shrink < 1, width > 0 and shrink x width < 1 (each restart
// narrows the working prior). The breach's setting: "shrink" or "width" (the
// filter.relinearize keys). OneStepFilter throws on it; the parser names the key.
SettingBreach relinearizeBreach(const RelinearizeSettings& s);

// Behaviour on data the model does not explain: the keys filter.support,
// filter.drift, filter.reopen and filter.relinearize (estimator_config.h
// reads them into this struct, whose support rule the batch methods take
// too; the one-step filter applies them all, OneStepSettings).
// filter.linearization: mean (moving_horizon.h).
struct MovingHorizonSettings {
  double window = 0.0;  // s; 0 = off (the collocation filter)
  double shift = 0.5;   // re-run when a linearisation point is further, in posterior std
  int reruns = 3;       // per window
  double step = 1e-4;   // finite-difference step, in prior std
  // s: prior std of a constant offset between the stamps of the predicted
  // channels (the IMU) and of the inputs (the suspension); 0 = not estimated.
  double clock_offset = 0.0;
  // Nuisance values (road-free roll plane with its IMU; 0 = not estimated),
  // prior stds of: the road's cross-fall at the start (rad: the whole
  // vehicle's tilt the travels do not see), its random walk (rad/sqrt(s)),
  // constant biases of accel_y and accel_z (m/s^2) and of gyro_x (rad/s).
  double cross_fall = 0.0;
  double cross_fall_walk = 0.0;
  double accel_bias = 0.0;
  double gyro_bias = 0.0;
  // The inputs' noise (road-free: the suspension readings the model reads)
  // carried as states, each input's at this sample and at the one before,
  // instead of each sample's inherited covariance alone: the noise of
  // a low-passed or averaged input is shared by the samples that follow
  // (Measurement::input_slopes).
  bool input_noise_states = false;
  // No reading changes when every mass, stiffness, damper rate and inertia
  // is scaled by one factor: each update's slope along that direction (at
  // the prior's mean) is set to 0, so that the scale keeps the prior's
  // information (filter.horizon.mass_scale_unobservable).
  bool mass_scale_unobservable = true;
  bool nuisance() const {
    return cross_fall > 0.0 || cross_fall_walk > 0.0 || accel_bias > 0.0 || gyro_bias > 0.0;
  }
};

// One estimated nuisance value (MovingHorizonSettings): its name in the
// estimate (cross_fall_rad, accel_y_bias, accel_z_bias, gyro_x_bias), mean and std.
struct NuisanceValue {
  std::string name;
  double mean = 0.0, stddev = 0.0;
};

struct SafeguardSettings {
  SupportRule support = SupportRule::kIgnore;
  Eigen::VectorXd drift;  // per parameter, random-walk std per sqrt(s) (empty = none)
  // Over an interval that ends at a standing sample (Measurement::standing):
  // filter.drift without drift_relative's share (dampers and tyres change
  // with the work they do, and a stop does none). Empty = drift.
  Eigen::VectorXd drift_standing;
  ReopenSettings reopen;
  RelinearizeSettings relinearize;  // one-step
  MovingHorizonSettings horizon;    // one-step, window > 0: linearised at the mean
};

// Largest gamma in [0, 1] such that before + gamma (after - before) keeps every
// mean strictly inside [lower, upper] (a margin of 1e-3 of the width; an
// infinite bound never binds). A mean already outside may only move inwards.
double supportDamping(const Eigen::VectorXd& before, const Eigen::VectorXd& after,
                      const Eigen::VectorXd& lower, const Eigen::VectorXd& upper);

// Random walk theta_i(t + dt) = theta_i(t) + w, Var(w) = intensity_i^2 dt,
// independent of everything else, without new germs. `x`: the extended state
// (rows x S), parameters from row `first_parameter`. The increment is added
// along a direction of the higher coefficients orthogonal to every other row
// and to the parameter's own: its variance grows by exactly intensity^2 dt and
// every covariance stays as it was. When no such direction is left (S - 1 <=
// rows), the parameter's higher coefficients are scaled instead
// (variance-matched inflation, correlations kept).
void applyDrift(Eigen::MatrixXd& x, int first_parameter, const Eigen::VectorXd& intensity,
                double dt);

// Parameter rows re-opened: kPrior -> the prior coefficients; kWidth -> the
// current mean with the prior's higher coefficients scaled by `width`.
void reopenParameters(Eigen::MatrixXd& theta, const Eigen::MatrixXd& prior,
                      const ReopenSettings& settings);

// Re-opens the parameter rows of the extended state `x` (parameters from row
// `first_parameter`) as reopenParameters does, and carries the states along:
// each state keeps its linear regression on the parameters (B = C_yt C_tt^-1
// from the higher coefficients), so the state widens with the parameters it
// depends on, and its residual, scaled by the largest factor by which a
// parameter's std grew (the states were fitted under those parameters).
// Re-opening the parameters alone would leave the state certain at values
// fitted with the old parameters; without process noise the data could then
// only correct the parameters, biasing them.
void reopenExtendedState(Eigen::MatrixXd& x, int first_parameter, const Eigen::MatrixXd& prior,
                         const ReopenSettings& settings);

}  // namespace pc_ekf
