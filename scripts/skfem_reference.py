#!/usr/bin/env python3
"""Independent scikit-fem reference data for the TLED hexahedron solver.

Writes ``verification/reference/skfem_neohookean.json``: internal nodal forces
of NiftySim's neo-Hookean material on distorted trilinear hexahedra, computed
by scikit-fem (a standard total-Lagrangian Galerkin assembly with 2x2x2 Gauss
quadrature), and a nonlinear static solution of a uniaxial-stretch problem.

Regenerate with::

    .venv/bin/python scripts/skfem_reference.py

Check that the committed file is what this script computes (the test command
does this; nothing is written)::

    .venv/bin/python scripts/skfem_reference.py --check

The check compares the structure, strings and integers exactly and every float
to 1e-13 of the largest magnitude of the same quantity (the same key path with
the list indices dropped, e.g. all ``homogeneous[].forces``): numpy's SIMD
kernels and the sparse solver sum in a CPU-dependent order, so a run on another
machine differs in the last bits (measured: up to 3e-16 of the quantity's
magnitude between an Intel Xeon and the machine that wrote the committed file),
while any change to what is computed moves the numbers by far more.  The Newton
residual is round-off by construction; it is only required to be below 1e-12 N
in both files.

Everything is deterministic: the only randomness (node perturbations) comes
from ``numpy.random.default_rng(SEED)``, and the package versions are pinned in
``scripts/requirements.txt``.

Node ordering
-------------
The JSON lists each hexahedron in VTK_HEXAHEDRON order (local node a at the
natural coordinates below).  scikit-fem's ``MeshHex1`` uses its own local
ordering (see the ``MeshHex1`` docstring and ``skfem/io/meshio.py``, whose
``HEX_MAPPING`` converts between the two).  In skfem's order the 8 local nodes
sit at the unit-cube corners (0,0,0) (0,0,1) (0,1,0) (1,0,0) (0,1,1) (1,0,1)
(1,1,0) (1,1,1).  Hence

    vtk_local[k]  = skfem_local[HEX_MAPPING[k]],   HEX_MAPPING = [0,3,6,2,1,5,7,4]
    skfem_local[j] = vtk_local[VTK_OF_SKFEM[j]],   VTK_OF_SKFEM = [0,4,3,1,7,5,2,6]

Note that ``ElementHex1`` attaches its basis function i to the reference
corner ``ElementHex1.doflocs[i]`` = (1,1,1), (1,1,0), ... which is the mirror
image (X -> 1 - X) of the corner layout above, so skfem's reference-to-global
Jacobian determinant is *negative* for a properly oriented element; skfem
integrates with ``abs(detDF)`` (``CellBasis.dx``).  Orientation is therefore
checked here with an independent VTK-order implementation, not with skfem.
"""

import json
import os
import re
import sys
import tempfile

import numpy as np
import scipy
import skfem
from scipy.optimize import brentq
from skfem import (Basis, BilinearForm, ElementHex1, ElementVector,
                   LinearForm, MeshHex1, asm, condense, solve)
from skfem.helpers import ddot, grad

SEED = 20240611
MU = 1000.0  # Pa
KAPPA = 10000.0  # Pa (bulk modulus K)
# skfem's ``intorder`` is the polynomial degree integrated exactly per
# direction; for hexahedra it uses ceil((intorder + 1) / 2) Gauss-Legendre
# points per direction (skfem.quadrature.get_quadrature_line), so intorder=3
# is the 2x2x2 Gauss rule.
INTORDER = 3

OUT_PATH = os.path.join(os.path.dirname(os.path.abspath(__file__)), os.pardir,
                        "verification", "reference", "skfem_neohookean.json")

# VTK_HEXAHEDRON natural coordinates of local node a.
VTK_XI = np.array([[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1],
                   [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]], dtype=float)
# skfem local node j is VTK local node VTK_OF_SKFEM[j]  (inverse of
# skfem.io.meshio.HEX_MAPPING[:8]).
VTK_OF_SKFEM = np.array([0, 4, 3, 1, 7, 5, 2, 6])

REL_TOL = 1e-12
N_LOAD_STEPS = 4  # for the static case


# --------------------------------------------------------------------------
# Material: NiftySim neo-Hookean,  W = mu/2 (J^-2/3 tr C - 3) + K/2 (J - 1)^2
# Tensors carry their two indices first and arbitrary trailing axes (skfem's
# layout for fields at quadrature points: (3, 3, n_elements, n_points)).
# --------------------------------------------------------------------------
def _inv(F):
    Fm = np.moveaxis(F, (0, 1), (-2, -1))
    return np.moveaxis(np.linalg.inv(Fm), (-2, -1), (0, 1))


def _det(F):
    return np.linalg.det(np.moveaxis(F, (0, 1), (-2, -1)))


def pk2(F, mu=MU, kappa=KAPPA):
    """S = mu J^-2/3 (I - trC/3 C^-1) + K J (J - 1) C^-1."""
    C = np.einsum("ki...,kj...->ij...", F, F)
    Ci = _inv(C)
    J = _det(F)
    trC = np.einsum("ii...->...", C)
    eye = np.eye(3).reshape((3, 3) + (1,) * (F.ndim - 2))
    return (mu * J ** (-2.0 / 3.0) * (eye - trC / 3.0 * Ci)
            + kappa * J * (J - 1.0) * Ci)


def pk1(F, mu=MU, kappa=KAPPA):
    """First Piola-Kirchhoff stress P = F S."""
    return np.einsum("ik...,kj...->ij...", F, pk2(F, mu, kappa))


def dpk1(F, mu=MU, kappa=KAPPA):
    """Material tangent A_iJkL = dP_iJ / dF_kL (derived from
    P = mu J^-2/3 (F - I1/3 F^-T) + K J (J - 1) F^-T, I1 = F:F)."""
    Fi = _inv(F)  # Fi[J, i] = (F^-1)_Ji
    J = _det(F)
    I1 = np.einsum("ij...,ij...->...", F, F)
    a = mu * J ** (-2.0 / 3.0)
    eye = np.eye(3)
    FiT = np.einsum("ji...->ij...", Fi)  # F^-T
    dev = F - I1 / 3.0 * FiT
    A = (-2.0 / 3.0 * a * np.einsum("iJ...,Lk...->iJkL...", dev, Fi)
         + a * np.einsum("ik,JL->iJkL...", eye, eye).reshape(
             (3, 3, 3, 3) + (1,) * (F.ndim - 2))
         - 2.0 / 3.0 * a * np.einsum("kL...,Ji...->iJkL...", F, Fi)
         + a * I1 / 3.0 * np.einsum("Jk...,Li...->iJkL...", Fi, Fi)
         + kappa * (2.0 * J ** 2 - J) * np.einsum("Lk...,Ji...->iJkL...", Fi, Fi)
         - kappa * (J ** 2 - J) * np.einsum("Jk...,Li...->iJkL...", Fi, Fi))
    return A


def check_material():
    """P = dW/dF and A = dP/dF by central finite differences."""
    def energy(F):
        J = np.linalg.det(F)
        return (MU / 2.0 * (J ** (-2.0 / 3.0) * np.sum(F * F) - 3.0)
                + KAPPA / 2.0 * (J - 1.0) ** 2)

    F = np.array([[1.1, 0.2, -0.05], [0.05, 0.9, 0.1], [-0.1, 0.15, 1.05]])
    P, A = pk1(F), dpk1(F)
    eps = 1e-6
    P_fd, A_fd = np.zeros((3, 3)), np.zeros((3, 3, 3, 3))
    for k in range(3):
        for l in range(3):
            dF = np.zeros((3, 3))
            dF[k, l] = eps
            P_fd[k, l] = (energy(F + dF) - energy(F - dF)) / (2 * eps)
            A_fd[:, :, k, l] = (pk1(F + dF) - pk1(F - dF)) / (2 * eps)
    assert np.allclose(P, P_fd, rtol=1e-6, atol=1e-6 * MU), (P, P_fd)
    assert np.allclose(A, A_fd, rtol=1e-6, atol=1e-6 * KAPPA)
    # Stress-free reference configuration and objectivity.
    assert np.abs(pk1(np.eye(3))).max() < 1e-12 * KAPPA


# --------------------------------------------------------------------------
# Independent trilinear hexahedron in VTK order (used to validate the node
# ordering conversion and element orientation).
# --------------------------------------------------------------------------
GAUSS_1D = np.array([-1.0, 1.0]) / np.sqrt(3.0)
GAUSS_XI = np.array([[a, b, c] for a in GAUSS_1D for b in GAUSS_1D
                     for c in GAUSS_1D])  # weights are all 1 on [-1, 1]^3


def vtk_dN_dxi(xi):
    """Natural derivatives (8, 3) of the VTK-ordered trilinear shape functions."""
    s = VTK_XI
    t = 1.0 + s * xi  # (8, 3)
    return 0.125 * np.stack([s[:, 0] * t[:, 1] * t[:, 2],
                             t[:, 0] * s[:, 1] * t[:, 2],
                             t[:, 0] * t[:, 1] * s[:, 2]], axis=1)


def vtk_element_direct(X):
    """Volume, (mean gradient (8, 3)), min detJ over Gauss points and corners
    for one hexahedron with VTK-ordered node coordinates X (8, 3)."""
    vol, int_grad, min_det = 0.0, np.zeros((8, 3)), np.inf
    for xi in GAUSS_XI:
        dN = vtk_dN_dxi(xi)
        Jm = X.T @ dN  # dx_i / dxi_j
        d = np.linalg.det(Jm)
        min_det = min(min_det, d)
        vol += d
        int_grad += dN @ np.linalg.inv(Jm) * d
    for xi in VTK_XI:
        min_det = min(min_det, np.linalg.det(X.T @ vtk_dN_dxi(xi)))
    return vol, int_grad / vol, min_det


# --------------------------------------------------------------------------
# Meshes (VTK connectivity, metres)
# --------------------------------------------------------------------------
def make_hex1_distorted(rng):
    """One ~10 mm cube with every corner moved by up to +-25 % of the edge in
    each coordinate; redrawn (deterministically) if it would be inverted."""
    edge = 0.01
    while True:
        X = (0.5 * (VTK_XI + 1.0) + rng.uniform(-0.25, 0.25, (8, 3))) * edge
        if vtk_element_direct(X)[2] > 0.0:
            return X, np.arange(8)[None, :]


def lattice_id(i, j, k, n=4):
    return i + n * j + n * n * k


def make_patch3_distorted(rng):
    """3x3x3 hexahedra on [0, 0.03]^3; the 8 interior nodes are moved by up to
    +-25 % of h in each coordinate, boundary nodes stay on the lattice."""
    n, L = 4, 0.03
    h = L / 3
    coords = np.linspace(0.0, L, n)  # exact 0 and L at the ends
    nodes = np.array([[coords[i], coords[j], coords[k]]
                      for k in range(n) for j in range(n) for i in range(n)])
    for k in (1, 2):
        for j in (1, 2):
            for i in (1, 2):
                nodes[lattice_id(i, j, k)] += rng.uniform(-0.25, 0.25, 3) * h
    elems = []
    for ez in range(3):
        for ey in range(3):
            for ex in range(3):
                elems.append([lattice_id(ex + int(a > 0), ey + int(b > 0),
                                         ez + int(c > 0))
                              for a, b, c in VTK_XI])
    return nodes, np.array(elems)


def to_skfem(nodes, elems_vtk):
    """MeshHex1 with the same node numbering and skfem-ordered elements."""
    mesh = MeshHex1(np.ascontiguousarray(nodes.T),
                    np.ascontiguousarray(elems_vtk[:, VTK_OF_SKFEM].T))
    assert np.array_equal(mesh.p, nodes.T)
    # The ordering itself is validated in element_geometry() against the
    # independent VTK-order implementation (volumes, mean gradients).
    basis = Basis(mesh, ElementHex1(), intorder=INTORDER)
    # Because skfem's reference cube is mirrored, its Jacobian
    # determinant is negative at every quadrature point of an element that is
    # positively oriented in VTK order (skfem integrates with |detDF|).
    assert (basis.mapping.detDF(basis.X) < 0).all()
    assert basis.X.shape[1] == 8, "expected 2x2x2 Gauss points"
    return mesh


# --------------------------------------------------------------------------
# scikit-fem forms (https://scikit-fem.readthedocs.io: LinearForm /
# BilinearForm, skfem.helpers.grad / ddot; the hyperelasticity example ex36
# uses the same structure).
# --------------------------------------------------------------------------
def _F(w):
    return np.eye(3)[:, :, None, None] + grad(w["u"])


@LinearForm
def internal_force(v, w):
    """f_n . v = int P(F) : grad v dV."""
    return ddot(pk1(_F(w)), grad(v))


@BilinearForm
def tangent(du, v, w):
    """int grad v : A(F) : grad du dV."""
    return np.einsum("ij...,ijkl...,kl...->...", grad(v), dpk1(_F(w)),
                     grad(du))


@LinearForm
def grad_x(v, w):
    return v.grad[0]


@LinearForm
def grad_y(v, w):
    return v.grad[1]


@LinearForm
def grad_z(v, w):
    return v.grad[2]


@LinearForm
def unit(v, w):
    return v


def vector_basis(mesh):
    return Basis(mesh, ElementVector(ElementHex1()), intorder=INTORDER)


def nodal_vector(basis, u_nodes):
    """(nnodes, 3) nodal array -> skfem DOF vector (via basis.nodal_dofs)."""
    x = np.zeros(basis.N)
    x[basis.nodal_dofs] = u_nodes.T
    return x


def nodal_array(basis, x):
    return x[basis.nodal_dofs].T.copy()


def assemble_forces(mesh, u_nodes):
    basis = vector_basis(mesh)
    x = nodal_vector(basis, u_nodes)
    return nodal_array(basis, asm(internal_force, basis, u=basis.interpolate(x)))


def single_element_mesh(nodes, elem_vtk):
    """A one-element skfem mesh for VTK element ``elem_vtk`` (local numbering
    0..7 = VTK order)."""
    return to_skfem(nodes[elem_vtk], np.arange(8)[None, :])


def element_geometry(nodes, elems):
    """Per element: volume and mean gradient (8, 3) in VTK order, from skfem,
    checked against the independent VTK-order implementation."""
    volumes, mean_grads = [], []
    for elem in elems:
        mesh = single_element_mesh(nodes, elem)
        sb = Basis(mesh, ElementHex1(), intorder=INTORDER)
        vol = float(np.sum(sb.dx))
        # Local node numbering of the one-element mesh equals VTK order, and
        # scalar ElementHex1 DOFs are the mesh nodes.
        int_grad = np.stack([asm(f, sb)[sb.nodal_dofs[0]]
                             for f in (grad_x, grad_y, grad_z)], axis=1)
        assert np.isclose(asm(unit, sb).sum(), vol, rtol=1e-14)
        vol_d, mg_d, min_det = vtk_element_direct(nodes[elem])
        assert min_det > 0.0, "inverted element"
        assert abs(vol - vol_d) <= 1e-13 * vol, (vol, vol_d)
        mg = int_grad / vol
        scale = np.abs(mg).max()
        assert np.abs(mg - mg_d).max() <= 1e-12 * scale
        # Partition of unity: sum_a grad N_a = 0.
        assert np.abs(mg.sum(axis=0)).max() <= 1e-12 * scale
        volumes.append(vol)
        mean_grads.append(mg)
    return np.array(volumes), np.array(mean_grads)


def rotation(axis, angle_deg):
    k = np.asarray(axis, dtype=float)
    k /= np.linalg.norm(k)
    th = np.radians(angle_deg)
    Kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(th) * Kx + (1 - np.cos(th)) * Kx @ Kx


HOMOGENEOUS_F0 = {
    "uniaxial_x_1.2": np.diag([1.2, 1.0, 1.0]),
    "simple_shear_xy_0.3": np.eye(3) + 0.3 * np.outer([1, 0, 0], [0, 1, 0]),
    "general": np.array([[1.1, 0.2, -0.05],
                         [0.05, 0.9, 0.1],
                         [-0.1, 0.15, 1.05]]),
    "rotation_30deg_about_123": rotation([1.0, 2.0, 3.0], 30.0),
    "triaxial_compression": np.diag([0.8, 0.9, 0.95]),
}


def homogeneous_cases(name, nodes, elems, volumes, mean_grads):
    cases = []
    for case, F0 in HOMOGENEOUS_F0.items():
        assert np.linalg.det(F0) > 0
        u = nodes @ (F0 - np.eye(3)).T  # u_n = (F0 - I) X_n
        forces = assemble_forces(to_skfem(nodes, elems), u)
        elem_forces = np.array([assemble_forces(single_element_mesh(nodes, e),
                                                u[e]) for e in elems])
        # Scattering the element forces reproduces the global assembly.
        scat = np.zeros_like(forces)
        for e, fe in zip(elems, elem_forces):
            np.add.at(scat, e, fe)
        # Force scale; MU is added so that the stress-free rotation case is
        # compared against a meaningful magnitude rather than zero.
        fscale = ((np.abs(pk1(F0)).max() + MU) * volumes.max()
                  * np.abs(mean_grads).max())
        assert np.abs(scat - forces).max() <= REL_TOL * fscale
        # The property the Rust TLED kernel relies on: for homogeneous F,
        # f_a = V_e P(F0) meanGrad_a  (component i: P_iJ g_aJ).
        pred = np.einsum("e,iJ,eaJ->eai", volumes, pk1(F0), mean_grads)
        err = np.abs(pred - elem_forces).max()
        assert err <= REL_TOL * fscale, (name, case, err, fscale)
        print(f"  {name:18s} {case:26s} max|f|={np.abs(forces).max():.3e} N"
              f"  |f_e - V P g|={err:.1e}")
        cases.append({"mesh": name, "name": case, "F0": F0.tolist(),
                      "u": u.tolist(), "forces": forces.tolist(),
                      "element_forces": elem_forces.tolist()})
    return cases


# --------------------------------------------------------------------------
# Static uniaxial stretch with roller boundary conditions
# --------------------------------------------------------------------------
def lateral_stretch(stretch):
    """lt such that F = diag(stretch, lt, lt) has S_yy = S_zz = 0."""
    def syy(lt):
        return pk2(np.diag([stretch, lt, lt]))[1, 1]
    return brentq(syy, 0.5, 1.5, xtol=1e-15, rtol=4 * np.finfo(float).eps,
                  maxiter=500)


def static_case(nodes, elems, strain=0.2, L=0.03):
    n = 4
    ids = np.arange(n ** 3).reshape(n, n, n)  # ids[k, j, i] = lattice_id(i,j,k)
    fix_x = np.sort(ids[:, :, 0].ravel())
    fix_y = np.sort(ids[:, 0, :].ravel())
    fix_z = np.sort(ids[0, :, :].ravel())
    pull_x = np.sort(ids[:, :, n - 1].ravel())
    assert np.all(nodes[fix_x, 0] == 0.0) and np.all(nodes[pull_x, 0] == L)
    assert np.all(nodes[fix_y, 1] == 0.0) and np.all(nodes[fix_z, 2] == 0.0)
    stretch = 1.0 + strain  # 1.2
    pull_value = strain * L  # 0.006 exactly as a double ((1.2-1)*L is not)

    mesh = to_skfem(nodes, elems)
    basis = vector_basis(mesh)
    D = np.concatenate([basis.nodal_dofs[0, fix_x], basis.nodal_dofs[1, fix_y],
                        basis.nodal_dofs[2, fix_z], basis.nodal_dofs[0, pull_x]])
    free = np.setdiff1d(np.arange(basis.N), D)
    x = np.zeros(basis.N)
    x[basis.nodal_dofs[0, pull_x]] = pull_value

    # Reaction-force scale: |P_xx| of the exact state times the loaded area.
    lt = lateral_stretch(stretch)
    F_exact = np.diag([stretch, lt, lt])
    force_scale = abs(pk1(F_exact)[0, 0]) * L * L
    tol = 1e-12 * force_scale

    # Newton's method with the consistent tangent assembled by skfem, under
    # load stepping: a single step diverges, because moving only the pulled
    # face by 20 % of L makes the initial tangent indefinite.  Each step
    # moves the Dirichlet values first and then iterates with zero Dirichlet
    # increments (skfem.condense).
    iters = 0
    pull_dofs = basis.nodal_dofs[0, pull_x]
    for step in range(1, N_LOAD_STEPS + 1):
        x[pull_dofs] = pull_value * step / N_LOAD_STEPS
        step_tol = tol if step == N_LOAD_STEPS else 1e-8 * force_scale
        for it in range(1, 31):
            uh = basis.interpolate(x)
            r = asm(internal_force, basis, u=uh)
            K = asm(tangent, basis, u=uh)
            x = x + solve(*condense(K, -r, D=D))
            iters += 1
            res = np.linalg.norm(asm(internal_force, basis,
                                     u=basis.interpolate(x))[free])
            print(f"  step {step} Newton {it}: |r_free|={res:.3e} N")
            if res < step_tol:
                break
        else:
            raise RuntimeError("Newton did not converge")

    u = nodal_array(basis, x)
    u_exact = nodes @ (F_exact - np.eye(3)).T
    err = np.abs(u - u_exact).max() / pull_value
    print(f"  lateral stretch {lt!r}; max|u - u_exact|/u_pull = {err:.2e};"
          f" residual/force scale = {res / force_scale:.2e}")
    assert err < 1e-10, err
    return {"mesh": "patch3_distorted", "stretch": stretch,
            "lateral_stretch": lt, "u": u.tolist(),
            "newton_iterations": iters, "residual_norm": float(res),
            "bc": {"fix_x": fix_x.tolist(), "fix_y": fix_y.tolist(),
                   "fix_z": fix_z.tolist(), "pull_x": pull_x.tolist(),
                   "pull_value": pull_value}}


CHECK_RTOL = 1e-13
ROUNDOFF_KEYS = {"residual_norm": 1e-12}


def _leaves(x, path, out):
    if isinstance(x, dict):
        for k, v in x.items():
            _leaves(v, f"{path}/{k}", out)
    elif isinstance(x, list):
        for i, v in enumerate(x):
            _leaves(v, f"{path}[{i}]", out)
    else:
        out.append((path, x))
    return out


def compare(committed, fresh):
    """Problems found comparing two reference dictionaries (empty: equal to
    round-off); prints the largest difference per quantity."""
    a = _leaves(committed, "", [])
    b = _leaves(fresh, "", [])
    if [p for p, _ in a] != [p for p, _ in b]:
        only = sorted(set(p for p, _ in a) ^ set(p for p, _ in b))
        return [f"different structure, e.g. {only[:3]}"]
    quantity = lambda p: re.sub(r"\[\d+\]", "[]", p)
    scale, worst, problems = {}, {}, []
    for p, v in a:
        if isinstance(v, float):
            q = quantity(p)
            scale[q] = max(scale.get(q, 0.0), abs(v))
    for (p, x), (_, y) in zip(a, b):
        q = quantity(p)
        key = q.rsplit("/", 1)[-1]
        if isinstance(x, float) and isinstance(y, float):
            if key in ROUNDOFF_KEYS:
                if max(abs(x), abs(y)) > ROUNDOFF_KEYS[key]:
                    problems.append(f"{p}: {x!r} / {y!r} above {ROUNDOFF_KEYS[key]}")
                continue
            d = abs(x - y) / scale[q] if scale[q] > 0 else abs(x - y)
            worst[q] = max(worst.get(q, 0.0), d)
            if d > CHECK_RTOL:
                problems.append(f"{p}: committed {x!r}, computed {y!r} "
                                f"({d:.1e} of the quantity's magnitude)")
        elif x != y:
            problems.append(f"{p}: committed {x!r}, computed {y!r}")
    for q, d in sorted(worst.items(), key=lambda kv: -kv[1])[:4]:
        print(f"  largest difference {d:.1e} of max|.| = {scale[q]:.2e}: {q}")
    return problems


def main():
    check = sys.argv[1:] == ["--check"]
    if sys.argv[1:] and not check:
        sys.exit(f"usage: {sys.argv[0]} [--check]")
    check_material()
    rng = np.random.default_rng(SEED)
    meshes = {"hex1_distorted": make_hex1_distorted(rng),
              "patch3_distorted": make_patch3_distorted(rng)}

    out = {"generator": "scripts/skfem_reference.py",
           "skfem_version": skfem.__version__,
           "numpy_version": np.__version__,
           "seed": SEED,
           "quadrature": "2x2x2 Gauss",
           "material": {"mu": MU, "K": KAPPA},
           "meshes": {}, "homogeneous": [], "elements": {}}
    print(f"scikit-fem {skfem.__version__}, numpy {np.__version__}, "
          f"scipy {scipy.__version__}, seed {SEED}")
    for name, (nodes, elems) in meshes.items():
        volumes, mean_grads = element_geometry(nodes, elems)
        # Element volumes tile the mesh volume (skfem's global assembly).
        total = asm(unit, Basis(to_skfem(nodes, elems), ElementHex1(),
                                intorder=INTORDER)).sum()
        assert abs(total - volumes.sum()) <= 1e-13 * total
        print(f"{name}: {len(nodes)} nodes, {len(elems)} elements, "
              f"volume {volumes.sum():.6e} m^3")
        out["meshes"][name] = {"nodes": nodes.tolist(),
                               "elements": elems.tolist()}
        out["elements"][name] = {"volume": volumes.tolist(),
                                 "mean_gradient": mean_grads.tolist()}
        out["homogeneous"] += homogeneous_cases(name, nodes, elems, volumes,
                                                mean_grads)
    print("static uniaxial stretch (patch3_distorted):")
    out["static"] = static_case(*meshes["patch3_distorted"])

    path = os.path.normpath(OUT_PATH)
    if check:
        with open(path) as f:
            committed = json.load(f)
        problems = compare(committed, json.loads(json.dumps(out)))
        if problems:
            print(f"{path} is not what scripts/skfem_reference.py computes "
                  f"({len(problems)} differences beyond round-off):", file=sys.stderr)
            for line in problems[:20]:
                print("  " + line, file=sys.stderr)
            sys.exit(1)
        print(f"{path}: equal to the computed data to round-off "
              f"(floats within {CHECK_RTOL} of each quantity's magnitude)")
        return
    os.makedirs(os.path.dirname(path), exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=os.path.dirname(path), suffix=".tmp")
    with os.fdopen(fd, "w") as f:
        json.dump(out, f, indent=1, allow_nan=False)
        f.write("\n")
    os.chmod(tmp, 0o644)
    os.replace(tmp, path)
    print(f"wrote {path} ({os.path.getsize(path)} bytes)")


if __name__ == "__main__":
    main()
