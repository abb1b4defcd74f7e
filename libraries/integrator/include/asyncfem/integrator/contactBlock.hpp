// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <asyncfem/core/vertexJacobian.hpp>
#include <asyncfem/stiffnessMatrix/dofs.hpp>
#include <cstddef>

namespace asyncfem {

/// What of the implicit external force's block k (stiffnessWeight * stiffness +
/// dampingWeight * damping of jacobian's vertex k) an implicit step matrix takes: its
/// symmetric part with the negative eigenvalues set to zero (friction couples the normal
/// and tangential directions unsymmetrically; a sphere's turning normal gives a negative
/// curvature term), the rows and columns of the vertex's fixed DOFs zeroed. The step matrix
/// stays symmetric positive definite (Cholesky, conjugate gradients); the iterations that
/// use it evaluate the force itself, so the projection changes their speed, not their
/// answer. Single-rate backward Euler weights it (h^2, h), the asynchronous integrator's
/// large system (hL^2, hL).
Eigen::Matrix3d contactStepBlock(const FreeDofs& dofs, const VertexJacobian& jacobian, std::size_t k,
                                 double stiffnessWeight, double dampingWeight);

/// jacobian with each coupling replaced by per-vertex blocks that bound it from above
/// (Gershgorin): at each of its vertices i, (stiffness, damping) |w_i| S N N^T, S the sum
/// of |w_j| over its vertices. What a step matrix whose pattern holds no off-diagonal
/// vertex blocks takes instead of the couplings (SurfaceContact::addJacobian's blocks).
VertexJacobian boundCouplings(const VertexJacobian& jacobian);

}  // namespace asyncfem
