// Compiled twin of biped_gait.core.dynamics.samples: many single-support states (q, qd), one per row, evaluated
// in one call with the same Pinocchio algorithms as the Python loop there. The stance tip is at the
// world origin; vectors are in world axes unless said otherwise. Units: m, rad, s, kg, N.
#include <pinocchio/multibody.hpp>
#include <pinocchio/algorithm/aba.hpp>
#include <pinocchio/algorithm/centroidal.hpp>
#include <pinocchio/algorithm/energy.hpp>
#include <pinocchio/algorithm/frames.hpp>
#include <pinocchio/algorithm/kinematics.hpp>
#include <pinocchio/algorithm/rnea.hpp>
#include <pinocchio/serialization.hpp>

#include <pybind11/eigen.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <limits>
#include <string>
#include <vector>

namespace py = pybind11;
using Vector = Eigen::VectorXd;
using Vector3 = Eigen::Vector3d;
using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
using Rows = Eigen::Ref<const RowMatrix>;
// Vectors reach Pinocchio's algorithms as Eigen::Ref<const VectorXd>, the argument type of the
// instantiations libpinocchio_default ships (PINOCCHIO_ENABLE_TEMPLATE_INSTANTIATION declares them
// extern): called with plain vectors, each algorithm would be compiled again here for every joint type.
using In = Eigen::Ref<const Vector>;

namespace {

pinocchio::Model load(const std::string& text) {
  pinocchio::Model model;
  model.loadFromString(text);
  return model;
}

// Eigen's quaternion of a rotation matrix, as (x, y, z, w): what pinocchio.Quaternion(R).coeffs() gives.
Eigen::Vector4d quaternion(const Eigen::Matrix3d& rotation) { return Eigen::Quaterniond(rotation).coeffs(); }

}  // namespace

class NativeSamples {
 public:
  // single_text, extended_text: pinocchio.Model.saveToString() of the 9-DOF single-support model and
  // the extended model (root translation first); swing_tip: frame id of the swing-foot tip;
  // pelvis: joint id of the pelvis, pelvis_offset: the pelvis centre in that joint's frame (m);
  // links: joint ids whose origins must stay above the ground;
  // arms: joint ids of the shoulders, whose hands are arm_length (m) down the joint's -z axis.
  NativeSamples(const std::string& single_text, const std::string& extended_text, int swing_tip, int pelvis,
                const Vector3& pelvis_offset, std::vector<int> links, std::vector<int> arms, double arm_length)
      : single_(load(single_text)),
        extended_(load(extended_text)),
        single_data_(single_),
        extended_data_(extended_),
        swing_tip_(swing_tip),
        pelvis_(pelvis),
        pelvis_offset_(pelvis_offset),
        links_(std::move(links)),
        arms_(std::move(arms)),
        hand_(0.0, 0.0, -arm_length),
        tau_(Vector::Zero(single_.nv)) {
    if (extended_.nq != single_.nq + 3) throw std::invalid_argument("the extended model must add a 3-DOF root");
  }

  // Per row: qdd by ABA (n x nq); [Fx, Fy, Fz, Mz] at the stance tip by RNEA of the extended model
  // with the root at rest (n x 4, N and N m); swing-tip height (m); yaw angular momentum about the
  // vertical through the stance tip (kg m^2/s); height of the lowest link joint or hand (m).
  py::tuple dynamics(Rows q, Rows qd) {
    const int n = rows(q, qd);
    RowMatrix qdd(n, single_.nv), grf(n, 4);
    Vector height(n), yaw(n), lowest(n);
    Vector x = Vector::Zero(extended_.nq), xd = Vector::Zero(extended_.nv), xdd = Vector::Zero(extended_.nv);
    py::gil_scoped_release release;  // no Python object is touched in the loop: other threads run meanwhile
    for (int i = 0; i < n; ++i) {
      const Vector qi = q.row(i).transpose(), qdi = qd.row(i).transpose();
      qdd.row(i) = pinocchio::aba(single_, single_data_, In(qi), In(qdi), In(tau_)).transpose();
      x.tail(single_.nq) = qi;
      xd.tail(single_.nv) = qdi;
      xdd.tail(single_.nv) = qdd.row(i).transpose();
      const Vector& tau = pinocchio::rnea(extended_, extended_data_, In(x), In(xd), In(xdd));
      grf.row(i) << tau[0], tau[1], tau[2], extended_data_.f[1].angular()[2];
      yaw[i] = angular_momentum(x, xd)[2];
      pinocchio::forwardKinematics(single_, single_data_, In(qi));
      height[i] = pinocchio::updateFramePlacement(single_, single_data_, swing_tip_).translation()[2];
      lowest[i] = lowest_link();
    }
    py::gil_scoped_acquire acquire;
    return py::make_tuple(qdd, grf, height, yaw, lowest);
  }

  // Per row: swing-tip height (m) and vertical velocity (m/s).
  py::tuple swing_tip_motion(Rows q, Rows qd) {
    const int n = rows(q, qd);
    Vector height(n), vz(n);
    for (int i = 0; i < n; ++i) {
      pinocchio::forwardKinematics(single_, single_data_, In(q.row(i).transpose()), In(qd.row(i).transpose()));
      height[i] = pinocchio::updateFramePlacement(single_, single_data_, swing_tip_).translation()[2];
      vz[i] = pinocchio::getFrameVelocity(single_, single_data_, swing_tip_, pinocchio::LOCAL_WORLD_ALIGNED)
                  .linear()[2];
    }
    return py::make_tuple(height, vz);
  }

  // Per row: pelvis position (n x 3, m) and orientation (n x 4, quaternion x, y, z, w; of M R M
  // with M = diag(1, -1, 1) when mirrored), pelvis velocity in the pelvis frame (n x 6: linear m/s,
  // angular rad/s), CoM (n x 3, m), linear momentum (n x 3, kg m/s), angular momentum about the
  // stance tip (n x 3, kg m^2/s).
  py::tuple poses(Rows q, Rows qd, bool mirrored) {
    const int n = rows(q, qd);
    RowMatrix position(n, 3), orientation(n, 4), velocity(n, 6), com(n, 3), momentum(n, 3), angular(n, 3);
    const Eigen::Vector3d mirror(1.0, mirrored ? -1.0 : 1.0, 1.0);
    Vector x = Vector::Zero(extended_.nq), xd = Vector::Zero(extended_.nv);
    py::gil_scoped_release release;  // no Python object is touched in the loop: other threads run meanwhile
    for (int i = 0; i < n; ++i) {
      x.tail(single_.nq) = q.row(i).transpose();
      xd.tail(single_.nv) = qd.row(i).transpose();
      pinocchio::forwardKinematics(single_, single_data_, In(x.tail(single_.nq)), In(xd.tail(single_.nv)));
      const pinocchio::SE3& pelvis = single_data_.oMi[pelvis_];
      position.row(i) = (pelvis.translation() + pelvis.rotation() * pelvis_offset_).transpose();
      const Eigen::Matrix3d rotation = mirror.asDiagonal() * pelvis.rotation() * mirror.asDiagonal();
      orientation.row(i) = quaternion(rotation).transpose();
      const pinocchio::Motion& twist = single_data_.v[pelvis_];
      velocity.row(i) << (twist.linear() + twist.angular().cross(pelvis_offset_)).transpose(),
          twist.angular().transpose();
      angular.row(i) = angular_momentum(x, xd).transpose();
      com.row(i) = extended_data_.com[0].transpose();
      momentum.row(i) = extended_data_.hg.linear().transpose();
    }
    py::gil_scoped_acquire acquire;
    return py::make_tuple(position, orientation, velocity, com, momentum, angular);
  }

  // Per row: kinetic plus gravitational potential energy (J), zero height at the stance tip.
  Vector energy(Rows q, Rows qd) {
    const int n = rows(q, qd);
    Vector out(n);
    for (int i = 0; i < n; ++i) {
      const Vector qi = q.row(i).transpose(), qdi = qd.row(i).transpose();
      out[i] = pinocchio::computeKineticEnergy(single_, single_data_, In(qi), In(qdi)) +
               pinocchio::computePotentialEnergy(single_, single_data_, In(qi));
    }
    return out;
  }

 private:
  int rows(const Rows& q, const Rows& qd) const {
    if (q.cols() != single_.nq || qd.cols() != single_.nv || q.rows() != qd.rows())
      throw std::invalid_argument("q and qd must be n x nq arrays of the same n");
    return static_cast<int>(q.rows());
  }

  // Angular momentum about the stance tip (the origin) at extended state (x, xd): h_G + c x p, as
  // the Python side writes it; leaves the CoM and h_G in the extended model's data.
  Vector3 angular_momentum(const Vector& x, const Vector& xd) {
    const pinocchio::Force& hg = pinocchio::computeCentroidalMomentum(extended_, extended_data_, In(x), In(xd));
    const Vector3& c = extended_data_.com[0];
    const Vector3 p = hg.linear();
    return hg.angular() + Vector3(c[1] * p[2] - c[2] * p[1], c[2] * p[0] - c[0] * p[2], c[0] * p[1] - c[1] * p[0]);
  }

  // Height (m) of the lowest of the link joints and hands, after forward kinematics.
  double lowest_link() const {
    double lowest = std::numeric_limits<double>::infinity();
    for (int j : links_) lowest = std::min(lowest, single_data_.oMi[j].translation()[2]);
    for (int j : arms_) lowest = std::min(lowest, single_data_.oMi[j].act(hand_)[2]);
    return lowest;
  }

  pinocchio::Model single_, extended_;
  pinocchio::Data single_data_, extended_data_;
  pinocchio::FrameIndex swing_tip_;
  pinocchio::JointIndex pelvis_;
  Vector3 pelvis_offset_;
  std::vector<int> links_, arms_;
  Vector3 hand_;
  Vector tau_;
};

// Placements of every joint of a model in its parent joint's frame (Pinocchio's liMi), for many
// configurations: translations (n x 3 (njoints - 1), m) and quaternions (n x 4 (njoints - 1), x, y, z, w).
class NativePlacements {
 public:
  explicit NativePlacements(const std::string& model_text) : model_(load(model_text)), data_(model_) {}

  py::tuple local(Rows q) {
    if (q.cols() != model_.nq) throw std::invalid_argument("q must be an n x nq array");
    const int n = static_cast<int>(q.rows()), joints = static_cast<int>(model_.njoints) - 1;
    RowMatrix translation(n, 3 * joints), orientation(n, 4 * joints);
    py::gil_scoped_release release;  // no Python object is touched in the loop: other threads run meanwhile
    for (int i = 0; i < n; ++i) {
      pinocchio::forwardKinematics(model_, data_, In(q.row(i).transpose()));
      for (int j = 0; j < joints; ++j) {
        const pinocchio::SE3& placement = data_.liMi[j + 1];
        translation.block<1, 3>(i, 3 * j) = placement.translation().transpose();
        orientation.block<1, 4>(i, 4 * j) = quaternion(placement.rotation()).transpose();
      }
    }
    py::gil_scoped_acquire acquire;
    return py::make_tuple(translation, orientation);
  }

 private:
  pinocchio::Model model_;
  pinocchio::Data data_;
};

PYBIND11_MODULE(_samples_native, m) {
  m.doc() = "Compiled evaluation of many biped states at once (see biped_gait/core/dynamics/samples.py).";
  py::class_<NativeSamples>(m, "NativeSamples")
      .def(py::init<const std::string&, const std::string&, int, int, const Vector3&, std::vector<int>,
                    std::vector<int>, double>(),
           py::arg("single_text"), py::arg("extended_text"), py::arg("swing_tip"), py::arg("pelvis"),
           py::arg("pelvis_offset"), py::arg("links"), py::arg("arms"), py::arg("arm_length"))
      .def("dynamics", &NativeSamples::dynamics, py::arg("q"), py::arg("qd"))
      .def("swing_tip_motion", &NativeSamples::swing_tip_motion, py::arg("q"), py::arg("qd"))
      .def("poses", &NativeSamples::poses, py::arg("q"), py::arg("qd"), py::arg("mirrored"))
      .def("energy", &NativeSamples::energy, py::arg("q"), py::arg("qd"));
  py::class_<NativePlacements>(m, "NativePlacements")
      .def(py::init<const std::string&>(), py::arg("model_text"))
      .def("local", &NativePlacements::local, py::arg("q"));
}
