// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <asyncfem/forceModel/forceModel.hpp>
#include <bindings.hpp>

namespace asyncfem::python {

/// A force model whose methods are written in Python (a subclass of asyncfem.ForceModel).
/// Integrators call it with the GIL released; each call takes the GIL, calls the Python
/// method and checks what it returned (ValueError naming the method on a wrong shape).
class PythonForceModel : public ForceModel {
 public:
  int numDofs() const override;
  bool isLinear() const override;
  Eigen::SparseMatrix<double> createStiffnessMatrix() const override;
  void internalForces(const Eigen::VectorXd& displacement, Eigen::VectorXd& forces) override;
  void tangentStiffness(const Eigen::VectorXd& displacement, Eigen::SparseMatrix<double>& stiffness) override;
  void forcesAndTangent(const Eigen::VectorXd& displacement, Eigen::VectorXd& forces,
                        Eigen::SparseMatrix<double>& stiffness) override;
  double elasticEnergy(const Eigen::VectorXd& displacement) override;
};

/// The shared_ptr a DynamicSystem stores for a force model given from Python: for a
/// Python subclass it also keeps the Python object (and so its methods and attributes)
/// alive for as long as C++ holds the model.
std::shared_ptr<ForceModel> forceModelFromPython(const py::object& model);

}  // namespace asyncfem::python
