// A mechanism pc_ekf does not know, estimated through its public model
// interface: the 2-DOF quarter car. A sprung mass m_s on a linear spring k and
// damper c over an unsprung mass m_u on a linear tyre k_t, riding one road
// contact y(t). Linear, so the deviations from the static equilibrium obey
//   m_s z_s'' = -k u - c v,   m_u z_u'' = k u + c v - k_t (z_u - y),
// with u = z_s - z_u (suspension extension) and v = u' (the two channels).
// The whole plugin: its description (table) and its right-hand side.
#include <pc_ekf/model/model_type.h>
#include <pc_ekf/model/pointwise_model.h>

#include <pluginlib/class_list_macros.hpp>

namespace pc_ekf_quarter_car {

class QuarterCarModel : public pc_ekf::PointwiseModel {
 public:
  static const pc_ekf::ModelDescription& describe() {
    using pc_ekf::nonNegative;
    using pc_ekf::positive;
    static const pc_ekf::ModelDescription d({
        "pc_ekf_quarter_car/QuarterCar",
        "2-DOF quarter car: a sprung mass on a linear spring and damper over an unsprung mass "
        "on a linear tyre.",
        pc_ekf::ParameterTable({{"sprung_mass", "kg", 300.0, positive(), "sprung mass m_s"},
                                {"unsprung_mass", "kg", 40.0, positive(), "unsprung mass m_u"},
                                {"spring", "N/m", 20000.0, positive(), "spring stiffness k"},
                                {"damping", "N s/m", 1500.0, nonNegative(), "damping c"},
                                {"tyre_stiffness", "N/m", 200000.0, positive(), "tyre k_t"}}),
        {},
        {},
        {"z_s", "z_u", "z_s_rate", "z_u_rate"},
        {{"u", "m", "suspension extension z_s - z_u"}, {"v", "m/s", "its rate"}},
        {{"wheel", "", "the one tyre"}},
        {{"quarter_suspension", "wheel", "u", "v"}},
    });
    return d;
  }

  QuarterCarModel(const Eigen::VectorXd& nominal, std::shared_ptr<const pc_ekf::ContactRoad> road)
      : PointwiseModel(describe(), nominal, observation(), std::move(road)) {}

  void pointDerivatives(double, const double* p, const double* road, const double* y,
                        double* dydt) const override {
    const double ms = p[0], mu = p[1], k = p[2], c = p[3], kt = p[4];
    const double f = -k * (y[0] - y[1]) - c * (y[2] - y[3]);  // suspension force on m_s
    dydt[0] = y[2];
    dydt[1] = y[3];
    dydt[2] = f / ms;
    dydt[3] = (-f - kt * (y[1] - road[0])) / mu;
  }

 private:
  static Eigen::MatrixXd observation() {  // u = z_s - z_u, v = its rate
    Eigen::MatrixXd h(2, 4);
    h << 1, -1, 0, 0, 0, 0, 1, -1;
    return h;
  }
};

using QuarterCarType = pc_ekf::PointwiseModelType<QuarterCarModel>;

}  // namespace pc_ekf_quarter_car

PLUGINLIB_EXPORT_CLASS(pc_ekf_quarter_car::QuarterCarType, pc_ekf::ModelType)
