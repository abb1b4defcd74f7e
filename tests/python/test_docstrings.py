# SPDX-License-Identifier: BSD-3-Clause
"""Every public function, class and method of asyncfem says what it is in help():
pybind11 writes the signature into __doc__ by itself, so a docstring counts only when it
has text beyond the signature lines (and beyond an enum's generated member list)."""
import inspect
import re

import asyncfem as af

SIGNATURE = re.compile(r"^\s*(\d+\.\s+)?[A-Za-z_][\w.]*\(.*\)\s*->\s*\S.*$")
GENERATED = ("Overloaded function.",)


def described(obj):
    """True when obj's __doc__ holds a sentence of its own, not only what pybind11 generates."""
    doc = inspect.getdoc(obj) or ""
    doc = doc.split("Members:")[0]  # pybind11 enums list their members after this line
    for line in doc.split("\n"):
        text = line.strip()
        if text and text not in GENERATED and not SIGNATURE.match(text):
            return True
    return False


def public_members(cls):
    """The public methods cls itself binds (not those of pybind11's base, nor enum members)."""
    for name, member in vars(cls).items():
        if name.startswith("_") or not callable(member):
            continue
        if isinstance(member, cls):  # an enum's value
            continue
        yield name, member


def undocumented():
    missing = []
    for name in sorted(dir(af)):
        obj = getattr(af, name)
        if name.startswith("_") or inspect.ismodule(obj) or not (callable(obj) or inspect.isclass(obj)):
            continue
        if not described(obj):
            missing.append(name)
        if inspect.isclass(obj):
            missing.extend(f"{name}.{member}" for member, value in public_members(obj) if not described(value))
    return missing


def test_every_public_callable_has_a_docstring():
    missing = undocumented()
    assert not missing, f"{len(missing)} without a docstring: " + ", ".join(missing)


def test_the_check_finds_a_missing_docstring():
    # The walk must see something: classes, functions and their members are many.
    assert described(af.lowest_modes) and described(af.Problem) and described(af.TetMesh.vertex_set)

    def bare(x):
        return x

    bare.__doc__ = "bare(x: int) -> int\n"
    assert not described(bare)
