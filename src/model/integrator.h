// Propagates a batch of model states (one column per collocation point) over
// an interval: an explicit Runge-Kutta method on a uniform grid within each
// kink-free segment, stopping exactly at the input's breakpoints (docs/method.md §1.5, §1.7).
#pragma once

#include <Eigen/Dense>
#include <string>

#include "pc_ekf/model/mechanical_model.h"

namespace pc_ekf {

enum class IntegrationMethod {
  kRk4,              // classical 4th-order Runge-Kutta, 4 evaluations per step
  kDormandPrince5,   // Dormand-Prince 5th-order solution, fixed step, 6 evaluations
                     // per step (first-same-as-last); same error as RK4 at ~1/2 the cost
};
std::string toString(IntegrationMethod m);  // "rk4", "dp5"
// Throws std::invalid_argument for an unknown name.
IntegrationMethod integrationMethodFromString(const std::string& name);

struct IntegratorSettings {
  double max_step = 1e-3;  // s
  IntegrationMethod method = IntegrationMethod::kRk4;
};

// Advances y (stateSize x Q) from t0 to t1 (t1 >= t0). Columns that become
// non-finite are left as they are (NaN/Inf) for the caller to report; the other
// columns are unaffected by them. Each column's result does not depend on the
// other columns of the batch.
void integrate(const MechanicalModel& model, const ModelBatch& batch, double t0, double t1,
               Eigen::ArrayXXd& y, const IntegratorSettings& settings);

}  // namespace pc_ekf
