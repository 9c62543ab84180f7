"""Forming the reduced camera system S = U − Σ_j W_j V_j⁻¹ W_jᵀ (the Schur complement).

Two ways, same S up to rounding (:func:`._choice.choose_formation`
picks one per structure):

* by pairs of rays (a, b) of the same point: block (image(a), image(b)) gains
  T_a W_bᵀ (T = W V⁻¹). Only the non-zero blocks are touched, which is what banded and
  sparse systems need; the cost is Σ_j k_j(k_j + 1)/2 pairs for points seen k_j times,
  formed per point by one batched BLAS product of the points of equal track length
  (:func:`._tracks.schur_blocks`).
* :func:`dense_schur` — for a dense S (small or densely connected networks): with the
  Cholesky factor V_j = L_j L_jᵀ of each point block, Y_a = W_a L_j⁻ᵀ gives
  W_j V_j⁻¹ W_jᵀ = Y_j Y_jᵀ, so Σ_j over a chunk of points is one product Y Yᵀ of a
  (6m × 3p_chunk) matrix — BLAS ``dsyrk``, far faster per flop than the pair-wise
  products. A network whose points are each seen by every image (pycolmap's
  ``visibility`` tracks) has Σ k_j² = m²·p: then the dense form does the same work.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg.blas as _blas
from numpy.typing import NDArray

F64 = NDArray[np.float64]
I64 = NDArray[np.int64]

#: Bytes of one chunk of the dense coupling matrix Y (6m × 3p_chunk) of :func:`dense_schur`.
DENSE_CHUNK_BYTES: int = 32 * 2**20
#: The scatter indices of :func:`dense_schur` are kept between iterations up to this many
#: entries (8 bytes each; 18 per ray).
DENSE_INDEX_KEEP: int = 2**21


#: A point's block V (symmetric positive semi-definite, 3 × 3) is numerically singular in
#: the directions whose eigenvalue is at most this fraction of its largest: the inverse
#: along them carries a relative error of ε/this (ε = 2.2e-16) and more — a point whose
#: rays have become parallel (receding to infinity along them; Ladybug's points that a
#: Cauchy loss lets recede reach it at ~1e10 model units), or seen only by rays a loss has
#: down-weighted to nothing. A well-determined point's smallest eigenvalue is 1e-4 to 1/3
#: of its largest.
SINGULAR_REL_EIG: float = 1e-12


def inv3(A: F64) -> F64:
    """Vectorised inverse of symmetric 3×3 matrices (n, 3, 3) by the adjugate.

    Raises ``ZeroDivisionError``-free: singular blocks give inf/NaN that callers check.
    """
    return _inv3(A)[0]


@dataclass
class HeldDepths:
    """The points whose block V is numerically singular (:data:`SINGULAR_REL_EIG`) and
    are held along their weak directions in a step.

    Attributes
    ----------
    points : ndarray of int, shape (h,)
        Their indices (point unknowns).
    factors : ndarray, shape (h, 3, 3)
        F with F Fᵀ = V⁺ (the inverse on the well-determined eigenvectors, 0 along the
        weak ones): the whitening factor :func:`dense_schur` uses for them.
    """

    points: I64
    factors: F64


def inv3_held(A: F64, rel_eig: float = SINGULAR_REL_EIG) -> tuple[F64, HeldDepths | None]:
    """:func:`inv3` of positive semi-definite blocks, where a block is numerically
    singular (an eigenvalue ≤ ``rel_eig`` times its largest) its inverse on the other
    eigenvectors instead, V⁺ = Σ vvᵀ/λ over the eigenvalues kept (0 along the weak
    ones). A point with V⁺ in place of V⁻¹ is held along its weak directions in the
    step (the elimination of the point reparametrised on the kept eigenvectors: T = W V⁺,
    its correction V⁺(…) has no component along them); its other coordinates are solved
    as any point's. Returns (the inverses (n, 3, 3), the held points or None).

    The blocks tested by eigenvalues are those with det ≤ ``rel_eig``/4·tr³ (λ₁λ₂ ≤
    tr²/4: no block with a weak eigenvalue passes it); the others keep :func:`inv3`'s
    values."""
    out, det = _inv3(A)
    tr = A[:, 0, 0] + A[:, 1, 1] + A[:, 2, 2]
    with np.errstate(over="ignore", invalid="ignore"):
        screen = np.flatnonzero(~(det > 0.25 * rel_eig * (tr * tr * tr)))
    if not screen.size:
        return out, None
    B = A[screen]
    finite = np.all(np.isfinite(B), axis=(1, 2))
    lam = np.zeros((screen.size, 3))
    vec = np.zeros((screen.size, 3, 3))
    if finite.any():
        lam[finite], vec[finite] = np.linalg.eigh(B[finite])
    top = lam[:, 2:]
    keep = lam > rel_eig * top  # (finite blocks; a zero or non-finite block keeps none)
    weak = ~np.all(keep, axis=1)
    if not weak.any():
        return out, None
    pts = screen[weak]
    lam, vec, keep = lam[weak], vec[weak], keep[weak]
    with np.errstate(divide="ignore"):
        root = np.where(keep, 1.0 / np.sqrt(np.where(keep, lam, 1.0)), 0.0)
    F = vec * root[:, None, :]  # columns v/√λ, 0 for the weak ones
    out[pts] = F @ F.transpose(0, 2, 1)
    return out, HeldDepths(pts, F)


def _inv3(A: F64) -> tuple[F64, F64]:
    """(:func:`inv3` of ``A``, the determinants)."""
    a, b, c = A[:, 0, 0], A[:, 0, 1], A[:, 0, 2]
    d, e, f = A[:, 1, 1], A[:, 1, 2], A[:, 2, 2]
    c00 = d * f - e * e
    c01 = c * e - b * f
    c02 = b * e - c * d
    det = a * c00 + b * c01 + c * c02
    out = np.empty_like(A)
    with np.errstate(divide="ignore", invalid="ignore"):
        r = 1.0 / det
        out[:, 0, 0] = c00 * r
        out[:, 0, 1] = out[:, 1, 0] = c01 * r
        out[:, 0, 2] = out[:, 2, 0] = c02 * r
        out[:, 1, 1] = (a * f - c * c) * r
        out[:, 1, 2] = out[:, 2, 1] = (b * c - a * e) * r
        out[:, 2, 2] = (a * d - b * b) * r
    return out, det


def gram_by_segments(J: F64, starts: I64, present: I64, m: int) -> F64:
    """Σ JᵀJ over the rays of each segment (image): (m, c, c) from J (n, 2, c) (the
    bundle's c = 7: the image blocks U and, in the last column, b_c).

    J holds the rays sorted by segment, ``starts`` where each non-empty segment begins,
    ``present`` which segment that is. One BLAS product (6 × 2k)(2k × 6) per segment of k
    rays: per-ray 6 × 6 products summed afterwards cost ~15 × more (a (n, 6, 6)
    intermediate and one tiny BLAS call per ray).
    """
    U = np.zeros((m, J.shape[2], J.shape[2]))
    A = J.reshape(-1, J.shape[2])
    bounds = np.append(starts, J.shape[0]) * J.shape[1]
    for s, (a, b) in enumerate(zip(bounds[:-1].tolist(), bounds[1:].tolist())):
        seg = A[a:b]
        U[present[s]] = seg.T @ seg
    return U


@dataclass
class ImageGram:
    """How the Gram matrices Σ JᵀJ per image are formed from rays in another order.

    Attributes
    ----------
    order, starts, present : ndarray of int
        The rays sorted by image, where each non-empty image begins, which image that is.
    m, n : int
        Numbers of images and rays.
    pad_max : float
        The Gram matrices are one stacked product over the rays padded to the largest
        count per image (zero rows) when that adds at most this fraction of rows; else
        one BLAS product per image (:func:`gram_by_segments`).
    slots : ndarray of int or None
        With padding: (len(present) · kmax,) the ray of each padded row (``n``: the zero
        row), image by image.
    """

    order: I64
    starts: I64
    present: I64
    m: int
    n: int
    pad_max: float = 0.5
    slots: I64 | None = None

    def __post_init__(self) -> None:
        counts = np.diff(np.append(self.starts, self.n))
        kmax = int(counts.max(initial=0))
        if self.present.size * kmax <= (1.0 + self.pad_max) * self.n and self.n:
            rank = np.arange(self.n) - np.repeat(self.starts, counts)
            seg = np.repeat(np.arange(self.present.size), counts)
            self.slots = np.full(self.present.size * kmax, self.n)
            self.slots[seg * kmax + rank] = self.order

    def grams(self, Jz: F64, rays: list | None = None) -> F64:
        """Σ JᵀJ per image (m, c, c) from ``Jz`` (n + 1, 2, c): the rays in their own
        order, then a zero row. ``rays``: a list to which the rays sorted by image are
        appended (:class:`ImageRays`, the array the products were formed from)."""
        c = Jz.shape[2]
        if self.slots is None:
            J = np.take(Jz[: self.n], self.order, axis=0)
            if rays is not None:
                counts = np.diff(np.append(self.starts, self.n))
                rays.append(ImageRays(J.reshape(-1, c), 2 * self.starts, 2 * counts, self))
            return gram_by_segments(J, self.starts, self.present, self.m)
        P = np.take(Jz, self.slots, axis=0).reshape(self.present.size, -1, c)
        if rays is not None:
            counts = np.diff(np.append(self.starts, self.n))
            starts = P.shape[1] * np.arange(self.present.size)
            rays.append(ImageRays(P.reshape(-1, c), starts, 2 * counts, self))
        G = np.matmul(P.transpose(0, 2, 1), P)
        if self.present.size == self.m:
            return G
        out = np.zeros((self.m, c, c))
        out[self.present] = G
        return out


@dataclass
class ImageRays:
    """The rays of :meth:`ImageGram.grams` sorted by image: each image's rows (2 per ray,
    in the order of :attr:`ImageGram.order`) are consecutive rows of one array.

    Attributes
    ----------
    rows : ndarray, shape (N, c)
        The rows (padded images: each image's block followed by zero rows).
    first, count : ndarray of int
        Per non-empty image (``gram.present``) where its rows begin and how many.
    gram : ImageGram
    """

    rows: F64
    first: I64
    count: I64
    gram: ImageGram

    def of_images(self) -> list[tuple[int, F64]]:
        """(image, its rows (2·rays, c): a view) of every image that has rays."""
        r, f, c = self.rows, self.first.tolist(), self.count.tolist()
        return [(i, r[a : a + k]) for i, a, k in zip(self.gram.present.tolist(), f, c)]


def whitening_factors(V: F64) -> F64:
    """F_j = L_j⁻ᵀ per point block (p, 3, 3), V_j = L_j L_jᵀ (Cholesky), so that
    (W F)(W F)ᵀ = W V⁻¹ Wᵀ. A block that is not positive definite gives NaN (the
    factorisation of S then reports it)."""
    a, b, c = V[:, 0, 0], V[:, 0, 1], V[:, 0, 2]
    d, e, f = V[:, 1, 1], V[:, 1, 2], V[:, 2, 2]
    F = np.zeros_like(V)
    with np.errstate(invalid="ignore", divide="ignore"):
        l00 = np.sqrt(a)
        l10, l20 = b / l00, c / l00
        l11 = np.sqrt(d - l10 * l10)
        l21 = (e - l20 * l10) / l11
        l22 = np.sqrt(f - l20 * l20 - l21 * l21)
        # L⁻¹ is lower triangular; F = (L⁻¹)ᵀ upper
        F[:, 0, 0] = 1.0 / l00
        F[:, 1, 1] = 1.0 / l11
        F[:, 2, 2] = 1.0 / l22
        F[:, 0, 1] = -l10 * F[:, 0, 0] * F[:, 1, 1]
        F[:, 1, 2] = -l21 * F[:, 1, 1] * F[:, 2, 2]
        F[:, 0, 2] = -(l20 * F[:, 0, 0] + l21 * F[:, 0, 1]) * F[:, 2, 2]
    return F


def dense_schur(st, U: F64, W: F64, V: F64, held: HeldDepths | None = None) -> tuple[F64, F64]:
    """S formed densely by chunks of points: S = U − Σ_chunks Y Yᵀ (lower triangle).

    Y_a = W_a F_j per ray (F_j = L_j⁻ᵀ, :func:`whitening_factors`: one stacked 6 × 3 · 3 × 3
    product per ray) is scattered into the (6m × 3p_chunk) matrix of a chunk of points
    by one flat index, and S gains −Y Yᵀ by BLAS ``dsyrk``.

    Parameters
    ----------
    st : orientviz.bundle.reduced.ReducedStructure
        The structure (its rays grouped by track length, ``st.tracks``; the blocks to
        return).
    U : ndarray, shape (m, 6, 6)
        Diagonal image blocks (damped).
    W : ndarray, shape (n_var, 6, 3)
        W_a = J_eᵀ P J_p per ray of a point unknown, in ``st.tracks.rays`` order.
    V : ndarray, shape (p_var, 3, 3)
        Point blocks (damped).
    held : HeldDepths, optional
        Points held along their weak directions in this step (:func:`inv3_held`): their
        factor F Fᵀ = V⁺.

    Returns
    -------
    blocks : ndarray, shape (n_blocks, 6, 6)
        The blocks (i ≤ k) of S (as :func:`orientviz.bundle.reduced._tracks.schur_blocks` returns
        them).
    S : ndarray, shape (6m, 6m), Fortran order
        S with a valid lower triangle (what the dense Cholesky reads and overwrites).
    """
    n = 6 * st.n_cam
    lay = _dense_layout(st)
    tg = st.tracks
    F = whitening_factors(V)
    if held is not None:
        F[held.points] = held.factors
    Y = W @ np.take(F, tg.ray_point, axis=0)
    S = np.zeros((n, n), order="F")
    S.reshape(-1, order="F")[lay.diag] = U.reshape(-1)
    for p0, p1, idx in lay.chunks():
        a0, a1 = lay.point_first[p0], lay.point_first[p1]
        Y2 = np.zeros((n, 3 * (p1 - p0)))
        Y2.reshape(-1)[idx] = Y[a0:a1].reshape(-1)
        # S ← S − Y2 Y2ᵀ (lower): BLAS sees the C-ordered Y2 as its transpose
        S = _blas.dsyrk(-1.0, Y2.T, beta=1.0, c=S, trans=1, lower=1, overwrite_c=1)
    blocks = S.reshape(-1, order="F")[lay.lower].reshape(-1, 6, 6)
    D = blocks[st.diag_block]  # diagonal blocks: S's lower half is their upper half here
    blocks[st.diag_block] = np.triu(D) + np.triu(D, 1).transpose(0, 2, 1)
    return blocks, S


@dataclass(frozen=True)
class _DenseLayout:
    """Constant index arrays of :func:`dense_schur` for one structure.

    ``ray_image``, ``ray_slot``: image and rank of the point of each ray (track order);
    ``point_first``: first ray of each point rank (and the end); ``diag``: flat (Fortran)
    index of the entries of the diagonal blocks, image-major; ``lower``: flat index of
    entry (r, c) of block (i ≤ k) in S's lower triangle, S[6k + c, 6i + r]
    (block-major, the transposed block: S holds block (i, k)ᵀ there).
    """

    ray_image: I64
    ray_slot: I64
    point_first: I64
    diag: I64
    lower: I64
    m: int
    _index: list = field(default_factory=list, repr=False)

    def chunks(self):
        """(first point rank, end, flat index into the chunk's (6m × 3p_chunk) matrix of
        every entry of the chunk's Y_a in ray order) per chunk of points; the indices are
        kept while they fit in :data:`DENSE_INDEX_KEEP` doubles."""
        if self._index:
            yield from self._index
            return
        pc = max(1, DENSE_CHUNK_BYTES // (8 * 18 * self.m))
        n_pt = self.point_first.size - 1
        r6x3 = np.arange(6)[:, None] * 3 + np.arange(3)  # row r, column c of a ray's Y_a
        keep = 18 * self.ray_image.size <= DENSE_INDEX_KEEP
        for p0 in range(0, n_pt, pc):
            p1 = min(p0 + pc, n_pt)
            a0, a1 = self.point_first[p0], self.point_first[p1]
            w = 3 * (p1 - p0)  # columns of the chunk
            # Y2[6 img + r, 3 (slot − p0) + c] = Y_a[r, c]
            base = self.ray_image[a0:a1] * (6 * w) + 3 * (self.ray_slot[a0:a1] - p0)
            idx = (base[:, None] + (r6x3 // 3 * w + r6x3 % 3).reshape(-1)).reshape(-1)
            if keep:
                self._index.append((p0, p1, idx))
            yield p0, p1, idx


def _dense_layout(st) -> _DenseLayout:
    """The :class:`_DenseLayout` of ``st`` (formed on first use, kept on ``st``)."""
    lay = vars(st).get("_dense_layout")
    if lay is not None:
        return lay
    tg = st.tracks
    m, n = st.n_cam, 6 * st.n_cam
    new_point = np.ones(tg.ray_point.size, bool)
    new_point[1:] = tg.ray_point[1:] != tg.ray_point[:-1]
    first = np.flatnonzero(new_point)
    r6 = np.arange(6)
    i6 = 6 * np.arange(m)[:, None, None]
    diag = ((i6 + r6[None, None, :]) * n + (i6 + r6[None, :, None])).reshape(-1)
    row = 6 * st.block_k[:, None, None] + r6[None, None, :]  # S row 6k + c
    col = 6 * st.block_i[:, None, None] + r6[None, :, None]  # S column 6i + r
    lay = _DenseLayout(
        tg.ray_image,
        np.cumsum(new_point) - 1,
        np.append(first, tg.ray_point.size),
        diag,
        (col * n + row).reshape(-1),
        m,
    )
    vars(st)["_dense_layout"] = lay
    return lay
