// Compiled twin of biped_gait.core.dynamics.flow.BallisticFlow.propagate: the same fixed-grid, 12-stage RK8
// scheme (Dormand-Prince DOP853 tableau, passed in by the Python side, core/dynamics/rk8_tableau.py) on the
// unactuated dynamics qdd = ABA(q, qd, 0), with the variational equations driven by
// Pinocchio's analytical ABA derivatives. Units: rad, rad/s, rad/s^2, s.
#include <pinocchio/multibody.hpp>
#include <pinocchio/algorithm/aba.hpp>
#include <pinocchio/algorithm/aba-derivatives.hpp>
#include <pinocchio/serialization.hpp>

#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <optional>
#include <string>
#include <tuple>
#include <vector>

namespace py = pybind11;
using Matrix = Eigen::MatrixXd;
using Vector = Eigen::VectorXd;
using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
// Vectors reach Pinocchio's algorithms as Eigen::Ref<const VectorXd>, the argument type of the
// instantiations libpinocchio_default ships (PINOCCHIO_ENABLE_TEMPLATE_INSTANTIATION declares them
// extern): called with plain vectors, each algorithm would be compiled again here for every joint type.
using In = Eigen::Ref<const Vector>;

class NativeFlow {
 public:
  // model_text: pinocchio.Model.saveToString(); a, b: the scheme's stage and weight
  // coefficients (stages x stages, stages); steps: grid steps per propagate call.
  NativeFlow(const std::string& model_text, const RowMatrix& a, const Vector& b, int steps)
      : a_(a), b_(b), steps_(steps) {
    if (steps < 1) throw std::invalid_argument("steps must be at least 1");
    if (a.rows() != a.cols() || a.rows() != b.size()) throw std::invalid_argument("inconsistent tableau");
    model_.loadFromString(model_text);
    data_ = pinocchio::Data(model_);
    tau_ = Vector::Zero(model_.nv);
  }

  Vector acceleration(const Vector& q, const Vector& qd) {
    return pinocchio::aba(model_, data_, In(q), In(qd), In(tau_));
  }

  // Returns (q(T), qd(T), sens (18 x k) or None, evaluations, nodes q, qd, qdd ((steps+1) x n) or None).
  py::tuple propagate(const Vector& q0, const Vector& qd0, double duration, std::optional<Matrix> seeds,
                      bool keep_nodes) {
    const int n = model_.nq;
    const int k = seeds ? static_cast<int>(seeds->cols()) : 0;
    const int stages = static_cast<int>(b_.size());
    if (q0.size() != n || qd0.size() != n) throw std::invalid_argument("q0 and qd0 must have the model's size");
    if (seeds && seeds->rows() != 2 * n) throw std::invalid_argument("seeds must have 2 nq rows");
    Matrix z(2 * n, 1 + k);
    z.col(0) << q0, qd0;
    if (k) z.rightCols(k) = *seeds;
    std::vector<Matrix> stage(stages, Matrix(2 * n, 1 + k));
    Matrix y(2 * n, 1 + k);
    const double h = duration / steps_;
    Matrix nq_, nqd_, nqdd_;
    if (keep_nodes) {
      nq_.resize(steps_ + 1, n);
      nqd_.resize(steps_ + 1, n);
      nqdd_.resize(steps_ + 1, n);
    }
    long evaluations = static_cast<long>(steps_) * stages;
    {
    py::gil_scoped_release release;  // no Python object is touched: other threads run meanwhile
    for (int step = 0; step < steps_; ++step) {
      for (int i = 0; i < stages; ++i) {
        y = z;
        for (int j = 0; j < i; ++j)
          if (a_(i, j) != 0.0) y.noalias() += (h * a_(i, j)) * stage[j];
        derivative(y, k, stage[i]);
      }
      if (keep_nodes) {
        nq_.row(step) = z.col(0).head(n).transpose();
        nqd_.row(step) = z.col(0).tail(n).transpose();
        nqdd_.row(step) = stage[0].col(0).tail(n).transpose();
      }
      for (int i = 0; i < stages; ++i)
        if (b_(i) != 0.0) z.noalias() += (h * b_(i)) * stage[i];
    }
    if (keep_nodes) {
      nq_.row(steps_) = z.col(0).head(n).transpose();
      nqd_.row(steps_) = z.col(0).tail(n).transpose();
      nqdd_.row(steps_) = acceleration(z.col(0).head(n), z.col(0).tail(n)).transpose();
      evaluations += 1;
    }
    }
    py::object nodes = py::none();
    if (keep_nodes) nodes = py::make_tuple(nq_, nqd_, nqdd_);
    py::object sens = py::none();
    if (k) sens = py::cast(Matrix(z.rightCols(k)));
    return py::make_tuple(Vector(z.col(0).head(n)), Vector(z.col(0).tail(n)), sens, evaluations, nodes);
  }

 private:
  // out = d/dt [[q, Sq], [qd, Sv]] = [[qd, Sv], [qdd, A_q Sq + A_v Sv]].
  void derivative(const Matrix& y, int k, Matrix& out) {
    const int n = model_.nq;
    out.topRows(n) = y.bottomRows(n);
    const Vector q = y.col(0).head(n), qd = y.col(0).tail(n);
    if (k) {
      pinocchio::computeABADerivatives(model_, data_, In(q), In(qd), In(tau_));
      out.col(0).tail(n) = data_.ddq;
      out.bottomRightCorner(n, k).noalias() = data_.ddq_dq * y.topRightCorner(n, k);
      out.bottomRightCorner(n, k).noalias() += data_.ddq_dv * y.bottomRightCorner(n, k);
    } else {
      out.col(0).tail(n) = pinocchio::aba(model_, data_, In(q), In(qd), In(tau_));
    }
  }

  pinocchio::Model model_;
  pinocchio::Data data_;
  Vector tau_;
  RowMatrix a_;
  Vector b_;
  int steps_;
};

PYBIND11_MODULE(_flow_native, m) {
  m.doc() = "Compiled fixed-grid RK8 ballistic flow with sensitivities (see biped_gait/flow.py).";
  py::class_<NativeFlow>(m, "NativeFlow")
      .def(py::init<const std::string&, const RowMatrix&, const Vector&, int>(), py::arg("model_text"),
           py::arg("a"), py::arg("b"), py::arg("steps"))
      .def("acceleration", &NativeFlow::acceleration)
      .def("propagate", &NativeFlow::propagate, py::arg("q0"), py::arg("qd0"), py::arg("duration"),
           py::arg("seeds") = py::none(), py::arg("keep_nodes") = false);
}
