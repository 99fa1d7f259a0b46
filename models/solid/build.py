"""Build a :class:`~iwan_element.models.solid.SolidSpecimen`: patches, assembly, reduction.

1. **Patches.** The lap (``x`` in ``[lap_start, beam_length]``, the full width) is cut into a
   grid of cells of about ``patch_size``; the bolts' cone pressure of the 1-D model
   (:func:`~iwan_element.models.specimens.contact.pressure_field`: same cone radius, shape and
   preload) is integrated over each cell, and cells without pressure are dropped. The lap
   plane is a contact only inside the cones: the rest of the lap is free, as in the 1-D model.
2. **Patch points.** Each body's displacement at a patch is the area average of its contact
   face over the patch's contact area, the part of the cell inside a bolt's contact annulus
   (``r_h <= r <= r_c``, where the pressure is non-zero): the face's linear interpolation
   integrated by 36 points per triangle, each point in the cell holding it (an RBE3-like
   average, not a rigid patch). Averaging the whole cell instead tied the face up to a
   cell's diagonal beyond ``r_c`` and in the bolt hole: with the patches tied stiffly, the
   first bending mode of the Brake-Reuss beam was 90.9 Hz instead of 85.6 Hz (6.4 mm patches;
   docs/solid.md). The rows of ``G`` are body B's average minus body A's, in ``x`` and ``y``
   (tangential slips); the normal rows (``z``, the gaps ``G_n``) carry a spring ``k_n A``
   per patch in ``K0``.
3. **Reduction.** The assembled bodies with the patches stuck (``K_ref = K0 + G^T diag(KT) G``
   at the specimen's stiffness per area) are reduced by a Ritz basis: the rigid-body modes,
   the lowest ``n_modes`` elastic modes of ``K_ref``, and one static attachment shape
   ``(K_ref + c M)^-1 [G; G_n]^T`` per tangential slip and per normal gap
   (``c = (2 pi 1 Hz)^2``, the mass shift that makes the free-free ``K_ref`` invertible; the
   loads are self-equilibrated). The basis is made mass-orthonormal and diagonalises
   ``K_ref``. Why: the kept modes of the stuck structure are exact (Ritz vectors that are
   eigenvectors), and the attachment shapes carry the static flexibility under the
   interface forces, tangential and normal (the static response to any patch force lies in
   the basis up to the mass shift), so both the tangential and the normal stiffness per
   area may change after the reduction (:meth:`SolidSpecimen.linear_system` rebuilds the
   reduced ``K0`` from the normal gaps); unlike a Craig-Bampton reduction with rigid (RBE2)
   patches, nothing stiffens the lap. Cost: one sparse factorisation of the full system;
   the reduced size is ``6 + n_modes + 3 n_patches``.
"""

from __future__ import annotations

import logging
import math
import time

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from iwan_element.base.validation import check_int, plain_number

from ..linear.system import LinearSystem
from ..specimens.contact import pressure_field
from ..specimens.presets import preset
from ..specimens.specimen import Specimen
from .mesh import SolidPart, lap_beam_parts
from .readout import _axis_grid, _point_row
from .specimen import PatchLayout, SolidModel, SolidSpecimen, clamp_stiffness, solid_contact_points

__all__ = ["patch_layout", "solid_specimen", "solid_preset"]

log = logging.getLogger(__name__)

_SHIFT = (2 * math.pi * 1.0) ** 2  # mass shift of the factorised K_ref [1/s^2]


def patch_layout(specimen: Specimen, *, patch_size: float) -> PatchLayout:
    """The contact patches of a specimen's lap: grid cells of about ``patch_size`` [m] with
    the cone pressure's force, contact area and the centroid of that area (module
    docstring, step 1).
    """
    s = specimen
    _check_build(s, patch_size, 1)
    nx = max(1, int(round(s.overlap / patch_size)))
    ny = max(1, int(round(s.width / patch_size)))
    k = 24  # pressure samples per cell and direction
    xg, yg, p = pressure_field(s, nx=nx * k, ny=ny * k)
    dA = (s.overlap / xg.size) * (s.width / yg.size)
    N = p.reshape(nx, k, ny, k).sum(axis=(1, 3)) * dA
    on = (p > 0).astype(float)
    n_on = on.reshape(nx, k, ny, k).sum(axis=(1, 3))
    A = n_on * dA
    Xg, Yg = np.meshgrid(xg + s.lap_start, yg, indexing="ij")
    with np.errstate(invalid="ignore", divide="ignore"):
        cx = (on * Xg).reshape(nx, k, ny, k).sum(axis=(1, 3)) / n_on
        cy = (on * Yg).reshape(nx, k, ny, k).sum(axis=(1, 3)) / n_on
    xc = s.lap_start + (np.arange(nx) + 0.5) * s.overlap / nx
    yc = (np.arange(ny) + 0.5) * s.width / ny - 0.5 * s.width
    X, Y = np.meshgrid(xc, yc, indexing="ij")
    keep = (N > 1e-9 * s.preload) & (A > 0)
    return PatchLayout(
        x=cx[keep],
        y=cy[keep],
        normal_force=N[keep],
        area=A[keep],
        preload=s.preload,
        size=(s.overlap / nx, s.width / ny),
        cells=np.column_stack([X[keep], Y[keep]]),
    )


def _in_contact(specimen: Specimen, xy: np.ndarray) -> np.ndarray:
    """Points (n, 2) of the lap plane [m] inside a bolt's contact annulus (``r_h <= r <= r_c``,
    where :func:`~iwan_element.models.specimens.contact.pressure_field` is non-zero).
    """
    s = specimen
    r = np.hypot(
        xy[:, None, 0] - s.lap_start - np.asarray(s.bolt_positions)[None, :], xy[:, None, 1]
    )
    return np.any((r >= 0.5 * s.bolt_diameter) & (r <= s.cone_radius), axis=1)


def _face_samples(part: SolidPart, n: int = 6):
    """Quadrature of the contact face: the centroids of each triangle's ``n^2`` congruent
    sub-triangles, ``(points (m, 2) [m], weights (m,) [m^2], nodes (m, 3), barycentric
    coordinates (m, 3))``: ``sum w u(point)`` integrates the linearly interpolated ``u``.
    """
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    up = i + j <= n - 1
    dn = i + j <= n - 2
    l1 = np.concatenate([(i[up] + 1 / 3), (i[dn] + 2 / 3)]) / n
    l2 = np.concatenate([(j[up] + 1 / 3), (j[dn] + 2 / 3)]) / n
    lam = np.column_stack([1 - l1 - l2, l1, l2])  # (n^2, 3)
    _, area = part.face_areas()
    P = part.positions[part.face_triangles][:, :, :2]  # (n_tri, 3, 2)
    pts = np.einsum("sk,tkd->tsd", lam, P).reshape(-1, 2)
    w = np.repeat(area / len(lam), len(lam))
    nodes = np.repeat(part.face_triangles, len(lam), axis=0)
    return pts, w, nodes, np.tile(lam, (len(area), 1))


def _patch_average(part: SolidPart, patches: PatchLayout, specimen: Specimen) -> sp.csr_matrix:
    """(n_patches, n_nodes) weights of the part's contact face averaged over each patch's
    contact area (the part of its cell inside a bolt's contact annulus).
    """
    pts, w, nodes, lam = _face_samples(part)
    on = _in_contact(specimen, pts)
    pts, w, nodes, lam = pts[on], w[on], nodes[on], lam[on]
    # the patch of each sample: the grid cell holding it (cells indexed from the lap's corner)
    hx, hy = patches.size
    origin = np.array([specimen.lap_start, -0.5 * specimen.width])
    ncell = np.round([specimen.overlap / hx, specimen.width / hy]).astype(int)
    key = np.clip(np.floor((pts - origin) / [hx, hy]).astype(int), 0, ncell - 1)
    ckey = np.round((patches.cells - origin) / [hx, hy] - 0.5).astype(int)
    lookup = np.full(ncell, -1)
    lookup[ckey[:, 0], ckey[:, 1]] = np.arange(len(patches))
    pat = lookup[key[:, 0], key[:, 1]]
    ok = pat >= 0
    W = sp.csr_matrix(
        ((w[ok, None] * lam[ok]).ravel(), (np.repeat(pat[ok], 3), nodes[ok].ravel())),
        shape=(len(patches), len(part.positions)),
    )
    W.sum_duplicates()
    tot = np.asarray(W.sum(axis=1)).ravel()
    if np.any(tot <= 0):
        empty = np.flatnonzero(tot <= 0)
        where = ", ".join(f"({patches.x[i]:.4g}, {patches.y[i]:.4g})" for i in empty[:4])
        raise ValueError(
            f"{empty.size} contact patches (at x, y = {where}{' ...' if empty.size > 4 else ''}"
            f" m) hold no part of part {part.name}'s contact face: either the part has no face "
            "where the specimen's bolts press (a hole, edge or cut of the mesh that the "
            "specimen's bolt_positions, bolt_diameter and washer_diameter do not describe: "
            "make them match the part), or its face is meshed coarser than the patch size "
            f"{patches.size} m (mesh it finer, lap_mesh_size, or enlarge patch_size)"
        )
    W = (sp.diags(1.0 / tot) @ W).tocsr()
    # least-norm correction of each patch's weights so that its point (the weighted node
    # position in the lap plane) is its contact area's centroid on both faces: a rigid-body
    # motion then makes no slip (G R = 0), which two independent meshes' averages miss
    for i in range(len(patches)):
        lo, hi = W.indptr[i], W.indptr[i + 1]
        P = part.positions[W.indices[lo:hi], :2].T
        C = np.vstack([np.ones(hi - lo), P - [[patches.x[i]], [patches.y[i]]]])
        w = W.data[lo:hi]
        W.data[lo:hi] = w - C.T @ np.linalg.lstsq(C @ C.T, C @ w - [1.0, 0.0, 0.0], rcond=None)[0]
    return W


def _slip_operator(specimen: Specimen, a: SolidPart, b: SolidPart, patches: PatchLayout):
    """(G_t, G_n): tangential slips (x, y per patch, interleaved) and normal gaps (z) of B's
    patch average minus A's, on the coordinates [A's, B's] (x, y, z per node).
    """
    Wa, Wb = _patch_average(a, patches, specimen), _patch_average(b, patches, specimen)

    def rows(d):
        ea = sp.kron(Wa, sp.csr_matrix(np.eye(3)[d]))
        eb = sp.kron(Wb, sp.csr_matrix(np.eye(3)[d]))
        return sp.hstack([-ea, eb]).tocsr()

    gx, gy, gz = rows(0), rows(1), rows(2)
    n = len(patches)
    order = np.arange(2 * n).reshape(2, n).T.ravel()  # x0, y0, x1, y1, ...
    return sp.vstack([gx, gy]).tocsr()[order], gz


def _clamp_nodes(specimen: Specimen, a: SolidPart) -> np.ndarray:
    """Beam A's end-face nodes (x = 0), empty for a free-free specimen."""
    if specimen.boundary == "free-free":
        return np.zeros(0, int)
    return np.nonzero(a.positions[:, 0] < 1e-9 * specimen.beam_length)[0]


def _fixed_coordinates(specimen: Specimen, a: SolidPart) -> np.ndarray:
    """Beam A's end face x = 0 held rigidly (clamped-free with no clamp springs in the
    setup); none free-free (checked by _check_build) or on clamp springs.
    """
    if specimen.setup.clamp is not None:
        return np.zeros(0, int)
    nodes = _clamp_nodes(specimen, a)
    return (3 * nodes[:, None] + np.arange(3)).ravel()


def _clamp_rows(specimen: Specimen, a: SolidPart, n: int) -> sp.csr_matrix:
    """(6, n) rows of the clamped face's rigid-body fit, translations ``x, y, z`` then
    rotations about ``x, y, z`` [m, rad]: the least-squares ``(t, w)`` of the face nodes'
    displacements ``u_i = t + w x (p_i - c)`` (``c`` the face centroid), on which a setup's
    clamp springs act (translational stiffness on ``t``, rotational on ``w``).
    """
    nodes = _clamp_nodes(specimen, a)
    r = a.positions[nodes] - a.positions[nodes].mean(axis=0)
    B = np.zeros((3 * nodes.size, 6))
    for i, (x, y, z) in enumerate(r):
        B[3 * i : 3 * i + 3, :3] = np.eye(3)
        B[3 * i : 3 * i + 3, 3:] = [[0.0, z, -y], [-z, 0.0, x], [y, -x, 0.0]]
    P = np.linalg.pinv(B)  # (6, 3 n_face)
    cols = (3 * nodes[:, None] + np.arange(3)).ravel()
    return sp.csr_matrix(
        (P.ravel(), (np.repeat(np.arange(6), cols.size), np.tile(cols, 6))), shape=(6, n)
    )


def _factor(A):
    """Solver of the sparse symmetric positive definite ``A``: NGsolve's sparse Cholesky
    (nested dissection; 2 s for 55k coordinates here) when NGsolve is installed, else
    SuperLU (about 10 x slower on 3-D meshes).
    """
    try:
        from ngsolve.la import SparseMatrixd
    except ImportError:
        lu = spla.splu(
            A.tocsc(),
            permc_spec="MMD_AT_PLUS_A",
            diag_pivot_thresh=0.0,
            options={"SymmetricMode": True},
        )
        return lu.solve
    C = A.tocoo()
    mat = SparseMatrixd.CreateFromCOO(C.row, C.col, C.data, A.shape[0], A.shape[1])
    inv = mat.Inverse(inverse="sparsecholesky")
    r, v = mat.CreateColVector(), mat.CreateColVector()

    def solve(b):
        b = np.asarray(b, float)
        cols = b.reshape(b.shape[0], -1)
        out = np.empty_like(cols)
        for k in range(cols.shape[1]):
            r.FV().NumPy()[:] = cols[:, k]
            v.data = inv * r
            out[:, k] = v.FV().NumPy()
        return out.reshape(b.shape)

    return solve


def _ritz_basis(K_ref, M, G_ports, n_keep):
    """Mass-orthonormal basis [modes, attachment shapes of the rows of ``G_ports``: the
    tangential slips and the normal gaps] diagonalising K_ref (step 3).
    """
    solve = _factor((K_ref + _SHIFT * M).tocsr())
    op = spla.LinearOperator(K_ref.shape, matvec=solve, dtype=float)
    w2, Phi = spla.eigsh(K_ref, k=n_keep, M=M, sigma=-_SHIFT, OPinv=op, which="LM")
    Psi = solve(np.asarray(G_ports.T.todense()))
    Psi /= np.sqrt(np.einsum("ij,ij->j", Psi, M @ Psi))
    T = np.hstack([Phi, Psi])
    lam, V = sla.eigh(T.T @ (M @ T))
    ok = lam > 1e-10 * lam.max()
    T = T @ (V[:, ok] / np.sqrt(lam[ok]))
    mu, Q = sla.eigh(T.T @ (K_ref @ T))
    return T @ Q, np.sort(w2)


def _check_build(specimen, patch_size, n_modes):
    """Refuse bad build options before any meshing."""
    if not isinstance(specimen, Specimen):
        raise TypeError(f"specimen must be a Specimen, got {type(specimen).__name__}")
    if specimen.boundary not in ("free-free", "clamped-free"):
        raise ValueError(
            f"specimen.boundary must be 'free-free' or 'clamped-free' for a solid "
            f"specimen, got {specimen.boundary!r}"
        )
    patch_size = plain_number(patch_size)
    if (
        isinstance(patch_size, bool)
        or not isinstance(patch_size, (int, float))
        or not 0 < patch_size <= specimen.overlap
    ):
        raise ValueError(
            f"patch_size must be a length in (0, overlap={specimen.overlap}] m, got {patch_size!r}"
        )
    check_int("n_modes", n_modes, 1)


def _full_system(specimen: Specimen, a: SolidPart, b: SolidPart, patches: PatchLayout):
    """Steps 1-2 on the full mesh: ``(M, K0, Kb, G_t, G_n, G_c, S, E, free)`` on the free
    coordinates (the clamped face's held ones left out), the normal springs and the setup's
    clamp springs in ``K0``.
    """
    Gt, Gn = _slip_operator(specimen, a, b, patches)
    kn = specimen.interface.normal_stiffness_per_area * patches.area
    M = sp.block_diag([a.M, b.M], format="csr")
    Kb = sp.block_diag([a.K, b.K], format="csr")
    K0 = (Kb + Gn.T @ sp.diags(kn) @ Gn).tocsr()
    S = _point_row(specimen, a, b, specimen.sensor_position)
    E = _point_row(specimen, a, b, specimen.excitation.position)
    fixed = _fixed_coordinates(specimen, a)
    free = np.setdiff1d(np.arange(M.shape[0]), fixed)
    Gc = (
        _clamp_rows(specimen, a, M.shape[0])
        if specimen.setup.clamp is not None
        else sp.csr_matrix((0, M.shape[0]))
    )
    M, K0, Kb, Gt, Gn, Gc, S, E = (
        M[free][:, free],
        K0[free][:, free],
        Kb[free][:, free],
        Gt[:, free],
        Gn[:, free],
        Gc[:, free],
        S[free],
        E[free],
    )
    if Gc.shape[0]:
        K0 = (K0 + Gc.T @ sp.diags(clamp_stiffness(specimen.setup.clamp)) @ Gc).tocsr()
    return M, K0, Kb, Gt, Gn, Gc, S, E, free


def solid_specimen(
    specimen: Specimen,
    parts: tuple,
    *,
    patch_size: float = 0.005,
    n_modes: int = 20,
    keep_full: bool = False,
) -> SolidSpecimen:
    """A :class:`SolidSpecimen` from a specimen and its two meshed halves.

    Parameters
    ----------
    specimen : Specimen
        Bolts, preload, interface law, sensor, boundary (``"free-free"`` or
        ``"clamped-free"``: beam A's end face ``x = 0`` clamped).
    parts : (SolidPart, SolidPart)
        Beam A and beam B in the assembly frame (:mod:`~iwan_element.models.solid.mesh`),
        each with its lap face as contact face.
    patch_size : float, keyword-only
        Contact patch size [m] (finer than the lap mesh: each patch must hold triangles of
        both faces).
    n_modes : int, keyword-only
        Elastic modes of the stuck structure kept in the reduction (``>= 1``).
    keep_full : bool, keyword-only
        Keep the full sparse matrices, the basis ``T`` (full free coordinates = ``T q``)
        and the free coordinates' indices on ``model.full`` (to check the reduction).
    """
    _check_build(specimen, patch_size, n_modes)
    if len(parts) != 2 or not all(isinstance(p, SolidPart) for p in parts):
        raise TypeError("parts must be two SolidPart (beam A, beam B)")
    t0 = time.perf_counter()
    a, b = parts
    patches = patch_layout(specimen, patch_size=patch_size)
    M, K0, Kb, Gt, Gn, Gc, S, E, free = _full_system(specimen, a, b, patches)
    KT = solid_contact_points(specimen, patches).KT
    K_ref = (K0 + Gt.T @ sp.diags(KT) @ Gt).tocsr()
    n_rigid = 6 if specimen.boundary == "free-free" else 0
    T, w2 = _ritz_basis(K_ref, M, sp.vstack([Gt, Gn, Gc]).tocsr(), n_rigid + n_modes)
    red = LinearSystem(
        M=T.T @ (M @ T),
        K0=T.T @ (K0 @ T),
        Kb=T.T @ (Kb @ T),
        G=Gt @ T,
        S=S @ T,
        free=np.arange(T.shape[1]),
        n_coordinates=T.shape[1],
        rigid_body_modes=n_rigid,
        E=E @ T,
    )
    axis = _axis_grid(specimen, a, b, T, free)
    info = {
        "n_full": int(M.shape[0]),
        "n_reduced": int(T.shape[1]),
        "n_modes": n_modes,
        "n_patches": len(patches),
        "patch_size": [float(v) for v in patches.size],
        "reduction_s": time.perf_counter() - t0,
        "stuck_frequencies_hz": (np.sqrt(np.abs(w2[n_rigid:])) / (2 * math.pi)).tolist(),
    }
    full = (
        {"M": M, "K0": K0, "Kb": Kb, "G": Gt, "Gn": Gn, "S": S, "basis": T, "free": free}
        if keep_full
        else None
    )
    log.info(
        "solid %s: %d -> %d coordinates, %d patches, %.2f s",
        specimen.name,
        M.shape[0],
        T.shape[1],
        len(patches),
        info["reduction_s"],
    )
    return SolidSpecimen(
        specimen,
        SolidModel(
            system=red,
            patches=patches,
            info=info,
            full=full,
            normal_gaps=Gn @ T,
            axis=axis,
            material=(specimen.youngs_modulus, specimen.density),
            clamp_rows=Gc @ T if Gc.shape[0] else None,
        ),
    )


def solid_preset(
    name: str,
    *,
    mesh_size: float = 0.008,
    lap_mesh_size: float | None = None,
    patch_size: float = 0.005,
    n_modes: int = 20,
    poissons_ratio: float = 0.3,
    holes: bool = True,
) -> SolidSpecimen:
    """A preset (:func:`~iwan_element.models.specimens.presets.preset`) as a solid specimen: its two
    halves meshed from its dimensions (:func:`~iwan_element.models.solid.lap_beam_parts`),
    patched and reduced (:func:`solid_specimen`). Needs the extra ``iwan-element[fem]``.

    Parameters
    ----------
    name : str
        A preset with boundary ``"free-free"`` or ``"clamped-free"``.
    mesh_size : float, keyword-only
        Largest element size [m].
    lap_mesh_size : float, optional, keyword-only
        Element size on the lap faces [m]; default ``min(mesh_size, patch_size / 2)``.
    patch_size, n_modes : keyword-only
        As :func:`solid_specimen`.
    poissons_ratio : float, keyword-only
    holes : bool, keyword-only
        Cut the bolt holes (:func:`~iwan_element.models.solid.lap_beam_parts`).
    """
    s = preset(name)
    _check_build(s, patch_size, n_modes)
    lms = min(mesh_size, 0.5 * patch_size) if lap_mesh_size is None else lap_mesh_size
    t0 = time.perf_counter()
    parts = lap_beam_parts(
        s, mesh_size=mesh_size, lap_mesh_size=lms, poissons_ratio=poissons_ratio, holes=holes
    )
    t_mesh = time.perf_counter() - t0
    solid = solid_specimen(s, parts, patch_size=patch_size, n_modes=n_modes)
    solid.model.info.update(
        mesh_s=t_mesh,
        mesh_size=mesh_size,
        lap_mesh_size=lms,
        poissons_ratio=poissons_ratio,
        holes=holes,
    )
    return solid
