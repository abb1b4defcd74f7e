// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/SparseCore>
#include <asyncfem/stiffnessMatrix/assembler.hpp>
#include <asyncfem/volumetricMesh/tetMesh.hpp>

namespace asyncfem {

/// Upper bound of the highest angular frequency omega_max of a tet mesh (linear FEM, or
/// corotational FEM at rest, whose tangent is the same K), with mass matrix of the given
/// type, in rad per time unit:
///
///     omega_max^2 = lambda_max(K, M) <= max_e lambda_max(K_e, M_e)
///
/// (K_e, M_e: 12x12 element stiffness and mass). Rigorous: x^T K x = sum_e x_e^T K_e x_e
/// <= sum_e lambda_e x_e^T M_e x_e <= (max_e lambda_e) x^T M x, and removing fixed DOFs
/// restricts x to a subspace, which can only lower lambda_max. The bound is usually
/// within a factor 1-2 of the true value. Throws asyncfem::ValidationError naming the
/// element if one has non-positive volume.
double estimateMaxFrequency(const TetMesh& mesh, MassType massType);

/// Estimate of omega_max from the free-DOF matrices alone (used when no mesh is at hand):
/// - diagonal (lumped) M: the Gershgorin bound of M^{-1} K,
///   omega_max^2 <= max_i sum_j |K_ij| / M_ii, rigorous;
/// - otherwise: power iteration on M^{-1} K (Rayleigh quotients converge from below),
///   increased by a 10% margin on omega_max^2. An estimate, not a bound: prefer the
///   element bound above when the mesh is known.
/// stiffness and mass: free-DOF matrices, symmetric, M positive definite.
double estimateMaxFrequency(const Eigen::SparseMatrix<double>& stiffness, const Eigen::SparseMatrix<double>& mass);

/// Stability limit h <= 2 / omega_max of central differences and symplectic Euler for an
/// undamped system (damping lowers the true limit somewhat: it is
/// (2 / omega) (sqrt(1 + xi^2) - xi) for modal damping ratio xi).
inline double stableTimestepFromFrequency(double maxFrequency) { return 2.0 / maxFrequency; }

}  // namespace asyncfem
