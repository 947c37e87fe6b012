// Propagates a batch of model states (one column per collocation point) over
// an interval: classical RK4 on a uniform grid within each kink-free segment,
// stopping exactly at the input's breakpoints (SPEC §1.5).
#pragma once

#include <Eigen/Dense>

#include "model/mechanical_model.h"

namespace pc_ekf {

struct IntegratorSettings {
  double max_step = 1e-3;  // s
};

// Advances y (stateSize x Q) from t0 to t1 (t1 >= t0). Columns that become
// non-finite are left as they are (NaN/Inf) for the caller to report; the other
// columns are unaffected by them.
void integrate(const MechanicalModel& model, const ModelBatch& batch, double t0, double t1,
               Eigen::ArrayXXd& y, const IntegratorSettings& settings);

}  // namespace pc_ekf
