// SPDX-License-Identifier: BSD-3-Clause
#include <algorithm>
#include <asyncfem/contact/penaltyContact.hpp>
#include <asyncfem/contact/surfaceContact.hpp>
#include <asyncfem/core/error.hpp>
#include <cmath>
#include <iterator>
#include <string>

namespace asyncfem {

PenaltyContact::PenaltyContact(Eigen::Matrix3Xd restPositions, std::vector<ContactPlane> planes,
                               std::vector<ContactSphere> spheres, PenaltyContactParameters parameters,
                               std::shared_ptr<const SurfaceContact> surfaces)
    : restPositions_(std::move(restPositions)),
      planes_(std::move(planes)),
      spheres_(std::move(spheres)),
      parameters_(parameters),
      surfaces_(std::move(surfaces)) {
  const PenaltyContactParameters& p = parameters_;
  if (!(p.stiffness > 0.0) || !std::isfinite(p.stiffness)) throw ValidationError("contact: stiffness must be > 0");
  if (!(p.damping >= 0.0) || !(p.friction >= 0.0) || !(p.frictionViscosity > 0.0)) {
    throw ValidationError("contact: damping and friction must be >= 0 and the friction viscosity > 0");
  }
  for (std::size_t i = 0; i < planes_.size(); ++i) {
    const double norm = planes_[i].normal.norm();
    if (!(norm > 0.0) || !std::isfinite(norm)) {
      throw ValidationError("contact: plane " + std::to_string(i) + " has a zero or non-finite normal");
    }
    // n . x >= offset is the allowed side; scale offset with the normal to keep the plane.
    planes_[i].normal /= norm;
    planes_[i].offset /= norm;
  }
  for (std::size_t i = 0; i < spheres_.size(); ++i) {
    if (!(spheres_[i].radius > 0.0))
      throw ValidationError("contact: sphere " + std::to_string(i) + " needs a radius > 0");
  }
}

template <class Visitor>
void PenaltyContact::forEachContact(const Eigen::VectorXd& displacement, const std::vector<int>* vertices,
                                    Visitor&& visit, double margin) const {
  const int n = static_cast<int>(restPositions_.cols());
  const int count = vertices ? static_cast<int>(vertices->size()) : n;
  for (int k = 0; k < count; ++k) {
    const int v = vertices ? (*vertices)[static_cast<std::size_t>(k)] : k;
    const Eigen::Vector3d x = restPositions_.col(v) + displacement.segment<3>(3 * v);
    for (const ContactPlane& plane : planes_) {
      const double depth = plane.offset - plane.normal.dot(x);
      if (depth > -margin) visit(v, depth, plane.normal, 0.0);
    }
    for (const ContactSphere& sphere : spheres_) {
      const Eigen::Vector3d r = x - sphere.center;
      const double distance = r.norm();
      const double depth = sphere.radius - distance;
      if (depth > -margin) {
        const Eigen::Vector3d normal = distance > 0.0 ? Eigen::Vector3d(r / distance) : Eigen::Vector3d::UnitY();
        visit(v, depth, normal, distance > 0.0 ? 1.0 / distance : 0.0);
      }
    }
  }
}

bool PenaltyContact::timeDependent() const { return surfaces_ && surfaces_->timeDependent(); }

void PenaltyContact::addForces(const Eigen::VectorXd& displacement, const Eigen::VectorXd& velocity,
                               Eigen::VectorXd& forces, const std::vector<int>* vertices) const {
  addForces(0.0, displacement, velocity, forces, vertices);
}

PenaltyContactJacobian PenaltyContact::jacobian(const Eigen::VectorXd& displacement, const Eigen::VectorXd& velocity,
                                                const std::vector<int>* vertices) const {
  return jacobian(0.0, displacement, velocity, vertices);
}

double PenaltyContact::energy(const Eigen::VectorXd& displacement) const { return energy(0.0, displacement); }

void PenaltyContact::addForces(double time, const Eigen::VectorXd& displacement, const Eigen::VectorXd& velocity,
                               Eigen::VectorXd& forces, const std::vector<int>* vertices) const {
  addPrimitiveForces(displacement, velocity, forces, vertices);
  if (surfaces_) surfaces_->addForces(time, displacement, velocity, forces, vertices);
}

void PenaltyContact::addForcesOfRank(double time, const Eigen::VectorXd& displacement, const Eigen::VectorXd& velocity,
                                     const std::vector<int>& vertices, const std::vector<int>& rank, int owner,
                                     Eigen::VectorXd& forces, PenaltyContactJacobian* jacobian) const {
  addPrimitiveForces(displacement, velocity, forces, &vertices);
  if (jacobian != nullptr) *jacobian = primitiveJacobian(displacement, velocity, &vertices);
  if (surfaces_) surfaces_->addForcesOfRank(time, displacement, velocity, rank, owner, forces, jacobian);
}

void PenaltyContact::addPrimitiveForces(const Eigen::VectorXd& displacement, const Eigen::VectorXd& velocity,
                                        Eigen::VectorXd& forces, const std::vector<int>* vertices) const {
  const PenaltyContactParameters& p = parameters_;
  forEachContact(displacement, vertices, [&](int v, double depth, const Eigen::Vector3d& normal, double) {
    const Eigen::Vector3d vel = velocity.segment<3>(3 * v);
    const double normalVelocity = vel.dot(normal);
    const double normalForce = std::max(0.0, p.stiffness * depth - p.damping * normalVelocity);
    Eigen::Vector3d f = normalForce * normal;
    if (p.friction > 0.0) {
      const Eigen::Vector3d tangential = vel - normalVelocity * normal;
      const double speed = tangential.norm();
      if (speed > 0.0) {
        const double magnitude = std::min(p.friction * normalForce, p.frictionViscosity * speed);
        f -= (magnitude / speed) * tangential;
      }
    }
    forces.segment<3>(3 * v) += f;
  });
}

PenaltyContactJacobian PenaltyContact::jacobian(double time, const Eigen::VectorXd& displacement,
                                                const Eigen::VectorXd& velocity,
                                                const std::vector<int>* vertices) const {
  PenaltyContactJacobian out = primitiveJacobian(displacement, velocity, vertices);
  if (surfaces_) surfaces_->addJacobian(time, displacement, velocity, out, vertices);
  return out;
}

PenaltyContactJacobian PenaltyContact::coupledJacobian(double time, const Eigen::VectorXd& displacement,
                                                       const Eigen::VectorXd& velocity) const {
  PenaltyContactJacobian out = primitiveJacobian(displacement, velocity, nullptr);
  if (surfaces_) surfaces_->addCoupledJacobian(time, displacement, velocity, out);
  return out;
}

PenaltyContactJacobian PenaltyContact::primitiveJacobian(const Eigen::VectorXd& displacement,
                                                         const Eigen::VectorXd& velocity,
                                                         const std::vector<int>* vertices) const {
  const PenaltyContactParameters& p = parameters_;
  PenaltyContactJacobian out;
  const Eigen::Matrix3d identity = Eigen::Matrix3d::Identity();
  forEachContact(displacement, vertices, [&](int v, double depth, const Eigen::Vector3d& n, double curvature) {
    const Eigen::Vector3d vel = velocity.segment<3>(3 * v);
    const double normalVelocity = vel.dot(n);
    const double normalForce = p.stiffness * depth - p.damping * normalVelocity;
    if (!(normalForce > 0.0)) return;  // clamped: no force, no derivative
    // dn/dx = curvature P (zero for a plane), P = I - n n^T; d depth/dx = -n^T.
    const Eigen::Matrix3d P = identity - n * n.transpose();
    const Eigen::Matrix3d turn = curvature * P;
    // f_n = k depth - c v.n: its gradients in x and v (row vectors).
    const Eigen::RowVector3d dNormalDx = -p.stiffness * n.transpose() - p.damping * vel.transpose() * turn;
    const Eigen::RowVector3d dNormalDv = -p.damping * n.transpose();
    // f = f_n n: df/dx = n df_n/dx + f_n dn/dx, df/dv = n df_n/dv.
    Eigen::Matrix3d dfdx = n * dNormalDx + normalForce * turn;
    Eigen::Matrix3d dfdv = n * dNormalDv;
    if (p.friction > 0.0) {
      // t = P v; dt/dv = P, dt/dx = -((v.n) I + n v^T) dn/dx.
      const Eigen::Vector3d tangential = vel - normalVelocity * n;
      const double speed = tangential.norm();
      if (speed > 0.0) {
        const Eigen::Matrix3d dtdx = -(normalVelocity * identity + n * vel.transpose()) * turn;
        if (p.frictionViscosity * speed <= p.friction * normalForce) {
          dfdx -= p.frictionViscosity * dtdx;  // f_t = -eta t
          dfdv -= p.frictionViscosity * P;
        } else {
          // f_t = -mu f_n t / |t|; d(t/|t|) = (I - t^ t^^T) dt / |t|.
          const Eigen::Vector3d direction = tangential / speed;
          const Eigen::Matrix3d project = (identity - direction * direction.transpose()) / speed;
          dfdx -= p.friction * (direction * dNormalDx + normalForce * project * dtdx);
          dfdv -= p.friction * (direction * dNormalDv + normalForce * project * P);
        }
      }
    }
    out.vertices.push_back(v);
    out.stiffness.push_back(-dfdx);
    out.damping.push_back(-dfdv);
  });
  return out;
}

double PenaltyContact::energy(double time, const Eigen::VectorXd& displacement) const {
  double squares = 0.0;
  forEachContact(displacement, nullptr,
                 [&](int, double depth, const Eigen::Vector3d&, double) { squares += depth * depth; });
  return (0.5 * parameters_.stiffness * squares) + (surfaces_ ? surfaces_->energy(time, displacement) : 0.0);
}

double PenaltyContact::maxPenetration(const Eigen::VectorXd& displacement) const {
  return maxPenetration(0.0, displacement);
}

double PenaltyContact::maxPenetration(double time, const Eigen::VectorXd& displacement) const {
  double worst = 0.0;
  forEachContact(displacement, nullptr,
                 [&](int, double depth, const Eigen::Vector3d&, double) { worst = std::max(worst, depth); });
  return surfaces_ ? std::max(worst, surfaces_->maxDepth(time, displacement)) : worst;
}

std::vector<int> PenaltyContact::verticesWithin(const Eigen::VectorXd& displacement, double margin) const {
  std::vector<int> out;
  forEachContact(
      displacement, nullptr,
      [&](int v, double, const Eigen::Vector3d&, double) {
        if (out.empty() || out.back() != v) out.push_back(v);
      },
      std::max(0.0, margin));
  if (surfaces_) {
    const std::vector<int> near = surfaces_->verticesWithin(0.0, displacement, margin);
    std::vector<int> merged;
    std::set_union(out.begin(), out.end(), near.begin(), near.end(), std::back_inserter(merged));
    return merged;
  }
  return out;
}

int PenaltyContact::activeContacts(const Eigen::VectorXd& displacement) const {
  if (surfaces_) return static_cast<int>(verticesWithin(displacement, 0.0).size());
  int count = 0;
  int last = -1;
  forEachContact(displacement, nullptr, [&](int v, double, const Eigen::Vector3d&, double) {
    if (v != last) ++count;
    last = v;
  });
  return count;
}

}  // namespace asyncfem
