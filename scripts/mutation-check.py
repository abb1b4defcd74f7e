#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""Mutation check: does the test suite notice a wrong formula?

Applies a fixed list of semantic mutations to the numerics, one at a time (a coupling
coefficient, a sign in a tangent, a mass weight, an off-by-one in a substep loop, a skipped
damping term, a dropped Jacobian block, a reader's index base, ...), rebuilds the test
executables that exercise the mutated code, runs their tests and records which tests fail
(the mutation's killers). A mutation no test notices is a survivor: docs/robustness.md lists
each one with why it is harmless or which test now kills it.

Usage (from the repository root, with a configured build folder whose tests are built):

    python3 scripts/mutation-check.py --build build [--only ID,ID] [--report FILE]
    python3 scripts/mutation-check.py --check           # every mutation applies exactly once

The source files are restored after each mutation (also on Ctrl-C); the script refuses to
start if a file it would mutate has uncommitted changes. Runs on demand, not in CI: each
mutation recompiles one file and relinks a few executables (about a minute on two cores).
"""

import argparse
import json
import re
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

# Test executables by what they exercise (the targets rebuilt and run for a mutation).
ELEMENT = ["stiffnessMatrixTests", "corotationalLinearFEMTests", "integratorTests", "vegaAgreementTests"]
SINGLE_RATE = ["integratorTests", "vegaAgreementTests"]
ASYNC = ["asyncIntegratorTests"]
HYPER = ["hyperelasticFEMTests", "vegaAgreementTests"]
CONTACT = ["contactTests", "integratorTests"]
READERS = ["volumetricMeshTests", "sceneIOTests"]
COROTATIONAL = ["corotationalLinearFEMTests", "vegaAgreementTests"]
COLLISION = ["collisionTests"]
CHECKPOINT = ["simulationIOTests", "offlineSimulatorTests", "resumeMatrixTests"]

ELEMENTS_CPP = "libraries/stiffnessMatrix/src/elementMatrices.cpp"
STEP_FORMULA = "libraries/integrator/include/asyncfem/integrator/stepFormula.hpp"
COUPLING = "libraries/asyncIntegrator/src/detail/coupling.cpp"
FAST_REGION = "libraries/asyncIntegrator/src/detail/fastRegion.cpp"
PENALTY = "libraries/contact/src/penaltyContact.cpp"
VEG = "libraries/volumetricMesh/src/detail/vegReader.cpp"
TETGEN = "libraries/volumetricMesh/src/detail/tetgenReader.cpp"
COROT = "libraries/corotationalLinearFEM/src/corotationalLinearFEM.cpp"
POLAR = "libraries/corotationalLinearFEM/src/polarDecomposition.cpp"
MATERIALS = "libraries/hyperelasticFEM/src/detail/isotropicMaterials.hpp"
BACKWARD_EULER = "libraries/integrator/src/backwardEuler.cpp"
CENTRAL = "libraries/integrator/src/centralDifferences.cpp"
SYMPLECTIC = "libraries/integrator/src/symplecticEuler.cpp"
HIERARCHY = "libraries/asyncIntegrator/src/detail/hierarchySystem.hpp"
PARTITION = "libraries/asyncIntegrator/src/regionPartition.cpp"
DISTANCE = "libraries/collision/src/distance.cpp"
BROAD = "libraries/collision/src/broadPhase.cpp"
CHECKPOINT_CPP = "libraries/simulationIO/src/checkpoint.cpp"


def mutation(ident, path, find, replace, what, targets):
    return {"id": ident, "file": path, "find": find, "replace": replace, "what": what, "targets": targets}


# Each mutation: a unique piece of source, what replaces it, and what the change breaks.
MUTATIONS = [
    # Element matrices (linear FEM, mass).
    mutation("lame-lambda", ELEMENTS_CPP, "((1.0 + poissonRatio) * (1.0 - 2.0 * poissonRatio))",
             "((1.0 + poissonRatio) * (1.0 - poissonRatio))", "Lame's lambda without the 2", ELEMENT),
    mutation("lame-mu", ELEMENTS_CPP, "youngsModulus / (2.0 * (1.0 + poissonRatio))",
             "youngsModulus / (1.0 + poissonRatio)", "shear modulus doubled", ELEMENT),
    mutation("consistent-mass-weight", ELEMENTS_CPP, "std::abs(volume) / 20.0", "std::abs(volume) / 24.0",
             "consistent mass scaled by 5/6", ELEMENT),
    mutation("consistent-mass-diagonal", ELEMENTS_CPP, "a == b ? 2.0 * offDiagonal", "a == b ? 1.0 * offDiagonal",
             "consistent mass diagonal weight 1 instead of 2", ELEMENT),
    mutation("lumped-mass-weight", ELEMENTS_CPP, "density * std::abs(volume) / 4.0",
             "density * std::abs(volume) / 3.0", "lumped mass weight 1/3 instead of 1/4", ELEMENT),
    mutation("shape-gradient-sum", ELEMENTS_CPP,
             "-(gradients.col(1) + gradients.col(2) + gradients.col(3))", "-(gradients.col(1) + gradients.col(2))",
             "grad N0 misses a term", ELEMENT),
    mutation("tet-volume", ELEMENTS_CPP, "*signedVolume = determinant / 6.0", "*signedVolume = determinant / 3.0",
             "tet volume doubled", ELEMENT),
    # Single-rate step formulas.
    mutation("be-matrix-damping", STEP_FORMULA, "return {1.0 + (h * alpha), (h * beta) + (h * h)};",
             "return {1.0 + (h * alpha), (h * h)};", "backward Euler matrix without stiffness damping",
             SINGLE_RATE + ASYNC),
    mutation("be-rhs-damping", STEP_FORMULA, "return {h, beta + h, 0.0, 0.0};", "return {h, h, 0.0, 0.0};",
             "backward Euler right-hand side without stiffness damping", SINGLE_RATE + ASYNC),
    mutation("be-matrix-mass-damping", STEP_FORMULA, "return {1.0 + (h * alpha), (h * beta) + (h * h)};",
             "return {1.0, (h * beta) + (h * h)};", "backward Euler matrix without mass damping",
             SINGLE_RATE + ASYNC),
    mutation("trapezoidal-weight", STEP_FORMULA, "inline double displacementWeight(double h) { return 0.25 * h * h; }",
             "inline double displacementWeight(double h) { return 0.5 * h * h; }",
             "trapezoidal displacement update weight h^2/2", SINGLE_RATE),
    mutation("be-update", BACKWARD_EULER,
             "Eigen::VectorXd newVelocity, newDisplacement, internal, residual, correction;\n"
             "  for (int iterations = 1;; ++iterations) {\n    newVelocity = v_ + dv_;",
             "Eigen::VectorXd newVelocity, newDisplacement, internal, residual, correction;\n"
             "  for (int iterations = 1;; ++iterations) {\n    newVelocity = v_;",
             "implicit-contact iterate moves with the old velocity", CONTACT),
    mutation("be-contact-blocks", BACKWARD_EULER,
             "if (!contact.empty()) free_->addVertexBlocks(system_.freeDofs, contact, h * h, h, stats_);",
             "if (!contact.empty()) free_->addVertexBlocks(system_.freeDofs, contact, h * h, 0.0, stats_);",
             "contact damping block dropped from the step matrix", CONTACT),
    mutation("central-half-step", CENTRAL, "  v_ += (0.5 * h) * newAcceleration;", "  v_ += h * newAcceleration;",
             "central differences' second half-kick doubled", SINGLE_RATE),
    mutation("symplectic-order", SYMPLECTIC, "  v_ += h * a_;\n  u_ += h * v_;", "  u_ += h * v_;\n  v_ += h * a_;",
             "symplectic Euler becomes explicit Euler", SINGLE_RATE),
    # Asynchronous coupling coefficients and the substep recurrence.
    mutation("stable-bK-off-by-one", COUPLING, "c.bK[k] = r * hS * hS;", "c.bK[k] = (r - 1) * hS * hS;",
             "stable coupling: off-by-one in the substep stiffness weight", ASYNC),
    mutation("stable-eK-off-by-one", COUPLING, "c.eK[k] = (m - r + 1) * hS * hS;", "c.eK[k] = (m - r) * hS * hS;",
             "stable coupling: off-by-one in the interface force average", ASYNC),
    mutation("stable-theta", COUPLING, "(m + 1.0) / (2.0 * m);", "(m + 1.0) / (2.0 * m + 1.0);",
             "stable coupling: interface weight theta", ASYNC),
    mutation("paper-bD", COUPLING, "c.bD[k] = r * hS / m;", "c.bD[k] = r * hS;",
             "paper coupling: damping weight not averaged", ASYNC),
    mutation("stable-bM", COUPLING, "c.bM[k] = r == 1 ? 1.0 : 0.0;", "c.bM[k] = 1.0;",
             "stable coupling: L's mass term at every substep", ASYNC),
    mutation("paper-eM", COUPLING, "        c.eM[k] = 1.0;\n        c.eD[k] = hL;",
             "        c.eM[k] = 1.0;\n        c.eD[k] = hS;", "paper coupling: end-of-step damping over hS", ASYNC),
    mutation("substep-rhs-weight", FAST_REGION, "rhsWeight = 1.0 / (1.0 + hS * alpha);", "rhsWeight = 1.0;",
             "substep recurrence ignores mass damping", ASYNC),
    mutation("substep-step-weight", FAST_REGION, "stepWeight = (1.0 + beta / hS) / (1.0 + hS * alpha);",
             "stepWeight = 1.0 / (1.0 + hS * alpha);", "substep recurrence ignores stiffness damping", ASYNC),
    mutation("substep-running-sum", FAST_REGION, "combined = runningStiffness + stepWeight * x.col(r - 2);",
             "combined = stepWeight * x.col(r - 2);", "forward substitution drops the running sum", ASYNC),
    mutation("fast-matrix-weight", FAST_REGION, "combineInto(0.0, Mss, hS * hS, Kss, G);",
             "combineInto(0.0, Mss, 2.0 * hS * hS, Kss, G);", "G = 2 hS^2 K instead of hS^2 K", ASYNC),
    mutation("hierarchy-step-containing", HIERARCHY,
             "return (t + unitsPerStep - 1) / unitsPerStep; }", "return t / unitsPerStep; }",
             "nested regions: a time unit falls in the previous step", ASYNC),
    mutation("partition-lcm", PARTITION, "units_ = std::lcm(units_, static_cast<long long>(count));",
             "units_ = std::max(units_, static_cast<long long>(count));", "nested regions: max instead of lcm",
             ASYNC),
    # Contact.
    mutation("contact-damping-sign", PENALTY, "std::max(0.0, p.stiffness * depth - p.damping * normalVelocity)",
             "std::max(0.0, p.stiffness * depth + p.damping * normalVelocity)", "contact damping pushes", CONTACT),
    mutation("friction-cap", PENALTY, "std::min(p.friction * normalForce, p.frictionViscosity * speed)",
             "std::max(p.friction * normalForce, p.frictionViscosity * speed)", "Coulomb cap becomes a floor",
             CONTACT),
    mutation("contact-jacobian-damping", PENALTY, "const Eigen::RowVector3d dNormalDv = -p.damping * n.transpose();",
             "const Eigen::RowVector3d dNormalDv = Eigen::RowVector3d::Zero();",
             "contact Jacobian drops the damping block", CONTACT + ASYNC),
    mutation("friction-jacobian-sign", PENALTY, "dfdx -= p.frictionViscosity * dtdx;",
             "dfdx += p.frictionViscosity * dtdx;", "sticking friction Jacobian sign", CONTACT),
    mutation("contact-energy", PENALTY, "return (0.5 * parameters_.stiffness * squares)",
             "return (parameters_.stiffness * squares)", "contact energy doubled", CONTACT),
    # Readers.
    mutation("veg-vertex-base", VEG, "const auto v = static_cast<std::size_t>(id - 1);",
             "const auto v = static_cast<std::size_t>(id % count);", "veg vertex index base", READERS),
    mutation("tetgen-base", TETGEN, "const auto v = static_cast<std::size_t>(id - base);",
             "const auto v = static_cast<std::size_t>(id > 0 ? id - 1 : id);",
             "TetGen numbering always one-based", READERS),
    # Corotational and hyperelastic models.
    mutation("corotational-stress", COROT, "Eigen::Matrix3d stressVolume = (2.0 * muVolume) * strain;",
             "Eigen::Matrix3d stressVolume = muVolume * strain;", "corotated stress loses the 2 of 2 mu eps",
             COROTATIONAL),
    mutation("corotational-energy", COROT, "(0.5 * lambdaVolume * trace * trace)",
             "(lambdaVolume * trace * trace)", "corotational energy lambda term doubled", COROTATIONAL),
    mutation("corotational-simple-tangent", COROT,
             "out.block<3, 3>(3 * a, 3 * b).noalias() = rotation * rotatedRight;",
             "out.block<3, 3>(3 * a, 3 * b).noalias() = rotatedRight;", "warp-1 tangent not rotated back",
             COROTATIONAL),
    mutation("polar-small-angle", POLAR, "if (angleSquared < 1e-8) {", "if (angleSquared < 1e-2) {",
             "Rodrigues' small-angle series used up to 0.1 rad", COROTATIONAL),
    mutation("neo-hookean-energy", MATERIALS,
             "out.energy = (0.5 * mu * (i1 - 3.0)) - (0.5 * mu * logI3) + (0.125 * lambda * logI3 * logI3);",
             "out.energy = (0.5 * mu * (i1 - 3.0)) - (0.5 * mu * logI3) + (0.25 * lambda * logI3 * logI3);",
             "neo-Hookean volumetric energy doubled", HYPER),
    mutation("neo-hookean-gradient", MATERIALS, "out.gradient[2] = ((-0.5 * mu) + (0.25 * lambda * logI3)) / i3;",
             "out.gradient[2] = ((-0.5 * mu) + (0.5 * lambda * logI3)) / i3;",
             "neo-Hookean dPsi/dI3 doubled volumetric term", HYPER),
    mutation("neo-hookean-hessian", MATERIALS,
             "out.hessian[2][2] = ((0.25 * lambda) + (0.5 * mu) - (0.25 * lambda * logI3)) / (i3 * i3);",
             "out.hessian[2][2] = ((0.25 * lambda) + (0.5 * mu)) / (i3 * i3);",
             "neo-Hookean d2Psi/dI3^2 drops a term", HYPER),
    mutation("stvk-energy", MATERIALS,
             "out.energy = (0.125 * lambda * (i1 - 3.0) * (i1 - 3.0)) + (0.25 * mu * (i2 - (2.0 * i1) + 3.0));",
             "out.energy = (0.125 * lambda * (i1 - 3.0) * (i1 - 3.0)) + (0.25 * mu * (i2 - (2.0 * i1) + 2.0));",
             "StVK energy off by a constant (forces unchanged)", HYPER),
    mutation("stvk-gradient", MATERIALS, "out.gradient[0] = (0.25 * lambda * (i1 - 3.0)) - (0.5 * mu);",
             "out.gradient[0] = (0.25 * lambda * (i1 - 3.0)) + (0.5 * mu);", "StVK dPsi/dI1 sign of the mu term",
             HYPER),
    # Collision geometry.
    mutation("point-line-distance", DISTANCE, "return r.squaredNorm() - s * s / e.squaredNorm();",
             "return r.squaredNorm() - s / e.squaredNorm();", "point-line squared distance", COLLISION),
    mutation("broad-phase-margin", BROAD, "boxes.max.col(p) = high.array() + margin;",
             "boxes.max.col(p) = high.array();", "broad phase boxes not inflated on one side", COLLISION),
    # Checkpoints.
    mutation("checkpoint-velocity", CHECKPOINT_CPP, "  read(checkpoint.velocity, counts.numDofs);",
             "  read(checkpoint.velocity, counts.numDofs);\n  checkpoint.velocity *= 1.0 + 1e-12;",
             "resumed velocity off by 1e-12 relative", CHECKPOINT),
]


def run(command, timeout, cwd=ROOT):
    try:
        done = subprocess.run(command, cwd=cwd, capture_output=True, text=True, timeout=timeout)
        return done.returncode, done.stdout + done.stderr
    except subprocess.TimeoutExpired as e:
        out = (e.stdout or b"").decode(errors="replace") if isinstance(e.stdout, bytes) else (e.stdout or "")
        return 124, out


def test_groups(build, targets):
    """The ctest groups (the part of a test's name before the dot) of the targets' tests."""
    code, out = run(["ctest", "--test-dir", str(build), "--show-only=json-v1"], 120)
    if code != 0:
        sys.exit("mutation-check: ctest --show-only failed in " + str(build) + ":\n" + out[-2000:])
    groups = set()
    for test in json.loads(out[out.index("{"):])["tests"]:
        command = test.get("command") or []
        if command and Path(command[0]).name in targets and "." in test["name"]:
            groups.add(test["name"].split(".")[0])
    return sorted(groups)


def failing_tests(output):
    return sorted(set(re.findall(r"^\s*\d+ - (\S+) \(", output, re.MULTILINE)))


def run_tests(build, targets, jobs):
    groups = test_groups(build, targets)
    if not groups:
        return None, [], "no tests found for " + ", ".join(targets)
    regex = "^(" + "|".join(re.escape(g) for g in groups) + r")\."
    code, out = run(["ctest", "--test-dir", str(build), "-R", regex, "-j", str(jobs), "--timeout", "300"], 3600)
    return code, failing_tests(out), out


def build_targets(build, targets):
    return run(["ninja", "-C", str(build)] + targets, 3600)


def check_applies(m):
    text = (ROOT / m["file"]).read_text()
    count = text.count(m["find"])
    if count != 1:
        return m["id"] + ": the text to mutate occurs " + str(count) + " times in " + m["file"]
    return None


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--build", default="build", help="configured build folder (default: build)")
    parser.add_argument("--only", default="", help="comma-separated mutation ids")
    parser.add_argument("--report", default="", help="write the markdown report here too")
    parser.add_argument("--jobs", type=int, default=2, help="ctest -j (default 2)")
    parser.add_argument("--check", action="store_true", help="only check that every mutation applies once")
    parser.add_argument("--list", action="store_true", help="list the mutations")
    args = parser.parse_args()

    chosen = MUTATIONS
    if args.only:
        wanted = set(args.only.split(","))
        chosen = [m for m in MUTATIONS if m["id"] in wanted]
        unknown = wanted - {m["id"] for m in chosen}
        if unknown:
            sys.exit("mutation-check: unknown mutation id(s): " + ", ".join(sorted(unknown)))
    ids = [m["id"] for m in MUTATIONS]
    if len(ids) != len(set(ids)):
        sys.exit("mutation-check: duplicate mutation ids")
    problems = [p for p in (check_applies(m) for m in chosen) if p]
    if problems:
        sys.exit("mutation-check: " + "\n".join(problems))
    if args.list:
        for m in chosen:
            print(f"{m['id']:32} {m['file']}: {m['what']}")
        return 0
    if args.check:
        print(f"mutation-check: all {len(chosen)} mutations apply exactly once")
        return 0

    build = (ROOT / args.build).resolve()
    files = sorted({m["file"] for m in chosen})
    dirty = subprocess.run(["git", "status", "--porcelain", "--"] + files, cwd=ROOT, capture_output=True,
                           text=True).stdout.strip()
    if dirty:
        sys.exit("mutation-check: these files have uncommitted changes; commit or stash them first:\n" + dirty)

    # The baseline: every executable builds and its tests pass before any mutation.
    all_targets = sorted({t for m in chosen for t in m["targets"]})
    code, out = build_targets(build, all_targets)
    if code != 0:
        sys.exit("mutation-check: the unmutated build fails:\n" + out[-3000:])
    baseline = {}
    for targets in sorted({tuple(m["targets"]) for m in chosen}):
        code, failed, out = run_tests(build, list(targets), args.jobs)
        if code is None or failed or code != 0:
            sys.exit("mutation-check: the unmutated tests of " + ", ".join(targets) + " do not pass: " +
                     ", ".join(failed) + "\n" + out[-2000:])
        baseline[targets] = True

    results = []
    for index, m in enumerate(chosen, 1):
        path = ROOT / m["file"]
        original = path.read_text()
        started = time.time()
        try:
            path.write_text(original.replace(m["find"], m["replace"], 1))
            code, out = build_targets(build, m["targets"])
            if code != 0:
                status, killers = "did not compile", []
            else:
                code, killers, out = run_tests(build, m["targets"], args.jobs)
                status = "killed" if (killers or code != 0) else "SURVIVED"
                if code != 0 and not killers:
                    killers = ["(ctest exit " + str(code) + ": crash or timeout)"]
        finally:
            path.write_text(original)
        seconds = time.time() - started
        results.append({**m, "status": status, "killers": killers, "seconds": seconds})
        print(f"[{index}/{len(chosen)}] {m['id']}: {status} in {seconds:.0f} s"
              f"{' by ' + ', '.join(killers[:3]) if killers else ''}{' ...' if len(killers) > 3 else ''}",
              flush=True)
    # Leave the build matching the sources again.
    build_targets(build, all_targets)

    compiled = [r for r in results if r["status"] != "did not compile"]
    killed = [r for r in compiled if r["status"] == "killed"]
    rate = 100.0 * len(killed) / len(compiled) if compiled else 0.0
    lines = [f"{len(killed)} of {len(compiled)} mutations killed ({rate:.1f}%)"
             f"{'; ' + str(len(results) - len(compiled)) + ' did not compile' if len(compiled) < len(results) else ''}",
             "", "| mutation | file | what it breaks | result | killed by (first 3 of N) |", "|---|---|---|---|---|"]
    for r in results:
        shown = ", ".join("`" + k + "`" for k in r["killers"][:3])
        more = f" ({len(r['killers'])})" if r["killers"] else ""
        lines.append(f"| `{r['id']}` | {Path(r['file']).name} | {r['what']} | {r['status']} | {shown}{more} |")
    report = "\n".join(lines)
    print("\n" + report)
    if args.report:
        Path(args.report).write_text(report + "\n")
    return 0 if rate >= 95.0 else 1


if __name__ == "__main__":
    sys.exit(main())
