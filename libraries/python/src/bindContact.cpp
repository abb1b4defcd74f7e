// SPDX-License-Identifier: BSD-3-Clause
// Penalty contact with static obstacles (library contact): ContactPlane, ContactSphere,
// PenaltyContactParameters and PenaltyContact, whose forces a Problem's loads carry.

#include <asyncfem/contact/penaltyContact.hpp>
#include <bindings.hpp>
#include <memory>
#include <optional>
#include <vector>

namespace asyncfem::python {

namespace {

/// The optional vertex filter of PenaltyContact's queries: None, or a list of vertex ids.
std::optional<std::vector<int>> vertexFilter(const py::handle& vertices) {
  if (vertices.is_none()) return std::nullopt;
  return indexListArgument(vertices, "vertices");
}

const std::vector<int>* pointer(const std::optional<std::vector<int>>& vertices) {
  return vertices ? &*vertices : nullptr;
}

void bindObstacles(py::module_& module) {
  py::class_<ContactPlane>(module, "ContactPlane",
                           "Static half-space obstacle {x : normal . x >= offset}; the body stays on the side "
                           "the normal points to")
      .def(py::init([](const Eigen::Vector3d& normal, double offset) {
             return ContactPlane{normal, offset};
           }),
           py::arg("normal") = Eigen::Vector3d::UnitY().eval(), py::arg("offset") = 0.0)
      .def_readwrite("normal", &ContactPlane::normal, "outward normal (normalised by PenaltyContact)")
      .def_readwrite("offset", &ContactPlane::offset, "normal . x on the plane (length)")
      .def("__repr__", [](const ContactPlane& p) {
        return "ContactPlane(normal=[" + std::to_string(p.normal.x()) + ", " + std::to_string(p.normal.y()) + ", " +
               std::to_string(p.normal.z()) + "], offset=" + std::to_string(p.offset) + ")";
      });
  py::class_<ContactSphere>(module, "ContactSphere", "Static solid sphere obstacle")
      .def(py::init([](const Eigen::Vector3d& center, double radius) {
             return ContactSphere{center, radius};
           }),
           py::arg("center") = Eigen::Vector3d::Zero().eval(), py::arg("radius") = 1.0)
      .def_readwrite("center", &ContactSphere::center, "centre (length)")
      .def_readwrite("radius", &ContactSphere::radius, "radius (length, > 0)");
  py::class_<PenaltyContactParameters>(module, "PenaltyContactParameters",
                                       "Penalty stiffness k, normal damping c, Coulomb friction mu and its "
                                       "regularising viscosity eta")
      .def(py::init<>())
      .def_readwrite("stiffness", &PenaltyContactParameters::stiffness, "k (force / length per vertex, > 0)")
      .def_readwrite("damping", &PenaltyContactParameters::damping, "c (force / velocity per vertex, >= 0)")
      .def_readwrite("friction", &PenaltyContactParameters::friction, "Coulomb coefficient mu (>= 0; 0: frictionless)")
      .def_readwrite("friction_viscosity", &PenaltyContactParameters::frictionViscosity,
                     "eta (force / velocity per vertex): viscous below the sliding threshold");
}

}  // namespace

void bindContact(py::module_& module) {
  bindObstacles(module);
  py::class_<PenaltyContact, std::shared_ptr<PenaltyContact>>(
      module, "PenaltyContact",
      "Penalty contact of the mesh vertices against static planes and spheres: a vertex at depth d > 0 gets "
      "(k d - c v.n) n (never pulling) plus, with friction, a regularised Coulomb force")
      .def(py::init([](const py::handle& restPositions, std::vector<ContactPlane> planes,
                       std::vector<ContactSphere> spheres, const PenaltyContactParameters& parameters) {
             const py::array_t<double> points = matrixArgument(restPositions, "rest_positions", -1, 3);
             Eigen::Matrix3Xd rest = Eigen::Map<const Eigen::Matrix3Xd>(points.data(), 3, points.shape(0));
             return std::make_shared<PenaltyContact>(std::move(rest), std::move(planes), std::move(spheres),
                                                     parameters);
           }),
           py::arg("rest_positions"), py::arg("planes") = std::vector<ContactPlane>{},
           py::arg("spheres") = std::vector<ContactSphere>{}, py::arg("parameters") = PenaltyContactParameters{},
           "rest_positions: (n, 3); raises ValueError for a non-positive stiffness, negative damping or friction, "
           "a zero plane normal or a non-positive sphere radius")
      .def(
          "forces",
          [](const PenaltyContact& contact, const py::handle& u, const py::handle& v, const py::handle& vertices) {
            const Eigen::VectorXd displacement = toVector(u, "displacement");
            const Eigen::VectorXd velocity = toVector(v, "velocity", displacement.size());
            const std::optional<std::vector<int>> filter = vertexFilter(vertices);
            Eigen::VectorXd forces = Eigen::VectorXd::Zero(displacement.size());
            contact.addForces(displacement, velocity, forces, pointer(filter));
            return forces;
          },
          py::arg("displacement"), py::arg("velocity"), py::arg("vertices") = py::none(),
          "contact forces (3n) at the state (u, v), both 3n; vertices: only these are tested (None: all)")
      .def(
          "energy",
          [](const PenaltyContact& contact, const py::handle& u) {
            return contact.energy(toVector(u, "displacement"));
          },
          py::arg("displacement"),
          "penalty potential k/2 sum d^2 at u (3n): the normal spring's force is minus its gradient")
      .def(
          "max_penetration",
          [](const PenaltyContact& contact, const py::handle& u) {
            return contact.maxPenetration(toVector(u, "displacement"));
          },
          py::arg("displacement"), "largest penetration depth at u (0 if none), length")
      .def(
          "active_contacts",
          [](const PenaltyContact& contact, const py::handle& u) {
            return contact.activeContacts(toVector(u, "displacement"));
          },
          py::arg("displacement"), "number of vertices in contact at u")
      .def(
          "vertices_within",
          [](const PenaltyContact& contact, const py::handle& u, double margin) {
            return intArray(contact.verticesWithin(toVector(u, "displacement"), margin));
          },
          py::arg("displacement"), py::arg("margin") = 0.0,
          "vertices (ascending) in contact at u or closer than margin (length, >= 0) to an obstacle")
      .def_property_readonly("parameters", &PenaltyContact::parameters, "k, c, mu and eta");
}

}  // namespace asyncfem::python
