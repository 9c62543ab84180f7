"""Self-calibrating bundle adjustment with parameter selection (a thin layer over the bundle).

:func:`self_calibrate` runs :func:`orientviz.bundle.bundle_adjust` with an
additional-parameter set (``additional=``; the bundle solves for the parameters itself)
and adds what practice needs around it (Ackermann §26: determinability of the
parameters; pseudo-observations against singularity):

1. adjust with all parameters of the set, each protected by a pseudo-observation
   ``p = 0 ± ap_sigma`` (µm);
2. test every parameter (:func:`orientviz.bundle.analyse`): parameters the
   block does not determine (held only by their pseudo-observation), parameters that are
   insignificant in every image group, and the weaker partner of every pair correlated
   above ``threshold``, are *suppressed* — their pseudo-observation σ is set to
   ``suppress_sigma`` so they stay (practically) at 0;
3. adjust again with the kept parameters.

If the set is not determinable at all (singular even with the pseudo-observations, or
without them), :class:`~orientviz.errors.NotDeterminableError` names the correlated
pairs found in a regularised trial run.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from ..adjust.result import Adjustment
from ..block import Block
from ..errors import InputError, NotDeterminableError
from .loop._adjust import bundle_adjust
from .model._additional import APAnalysis, analyse, ap_set
from .model._lens import KINDS, LensModel

__all__ = ["SelfCalibration", "self_calibrate"]


@dataclass
class SelfCalibration:
    """Result of :func:`self_calibrate`.

    Attributes
    ----------
    adjustment : Adjustment
        The final adjustment (kept parameters free within ``ap_sigma``).
    first : Adjustment
        The adjustment with all parameters.
    analysis : APAnalysis
        Tests of the first adjustment (the basis of the selection).
    final_analysis : APAnalysis
        Tests of the final adjustment.
    aps : AdditionalParameters
        The parameter set.
    kept, suppressed : list of str
        Parameter names (of the set, without group suffix) kept free and suppressed.
    reasons : dict of str to str
        Why each suppressed parameter was suppressed.
    correlated : list of str
        Pairs correlated above the threshold whose partners were both kept.
    """

    adjustment: Adjustment
    first: Adjustment
    analysis: APAnalysis
    final_analysis: APAnalysis
    aps: object
    kept: list[str]
    suppressed: list[str]
    reasons: dict[str, str] = field(default_factory=dict)
    correlated: list[str] = field(default_factory=list)

    def summary(self) -> str:
        """A few lines: σ0 before/after selection, kept and suppressed parameters."""
        lines = [
            f"{self.aps.name}: σ0 {self.first.sigma0:.3f} (all {len(self.aps.names)}) → "
            f"{self.adjustment.sigma0:.3f} (kept {len(self.kept)}) [a-priori units]",
            "kept: " + (", ".join(self.kept) or "none"),
        ]
        lines += [f"suppressed {k}: {v}" for k, v in self.reasons.items()]
        if self.correlated:
            lines.append("correlated above the threshold: " + ", ".join(self.correlated))
        cam = getattr(self.adjustment, "camera", None)
        if cam is not None:
            lines.append(cam.table())
        return "\n".join(lines)


def _base(name: str) -> str:
    return name.split("@", 1)[0]


#: Format side (mm) of the aerial camera the µm defaults were set for (23 cm film).
AERIAL_FORMAT_MM = 230.0
#: Pseudo-observation σ of the additional-parameter sets for that camera, µm.
AERIAL_AP_SIGMA_UM = 10.0
#: Pseudo-observation σ of a lens model's parameters, as a fraction of r0 (weak: a
#: guard against singularity, not a prior; a phone lens moves points by 1-3 % of r0).
LENS_SIGMA_OF_R0 = 0.1


def camera_defaults(block: Block) -> dict[str, float]:
    """What the defaults of :func:`self_calibrate` follow: the first camera's principal
    distance ``c``, shorter format side ``side`` (mm) and reference radius ``r0`` (mm:
    the RMS distance of the image points from the principal point, 2 digits)."""
    cam = block.cameras
    c = float(cam.c[0])
    side = float(np.min(cam.format_mm[0]))
    xy = block.observations.xy[block.images.camera[block.observations.image] == 0]
    d = xy - [cam.x0[0], cam.y0[0]]
    rms = float(np.sqrt(np.mean(np.sum(d * d, axis=1)))) if d.size else side / 2
    return {"c": c, "side": side, "r0": float(f"{rms:.2g}")}


def default_set(name: str, block: Block):
    """The set ``name`` sized for the block's camera: Ebner's and Grün's image base
    b = 0.4 × the shorter format side (92 mm for 23 cm), Brown's c and r0 from the
    camera, ``"backward"``/``"forward"``: a :class:`~orientviz.bundle.LensModel`."""
    key = str(name).lower().replace("-", "").replace("_", "")
    if key in KINDS:
        return LensModel(key)
    d = camera_defaults(block)
    if key == "brown":
        return ap_set(key, c=d["c"], r0=d["r0"])
    if key in ("ebner12", "gruen44"):
        return ap_set(key, b=0.4 * d["side"])
    return ap_set(name)  # an unknown name: ap_set's message


def default_ap_sigma(aps, block: Block) -> float:
    """σ (µm) of the pseudo-observations p = 0: 10 µm for a 23 cm aerial format, scaled
    with the format side, for Ebner's and Grün's sets (film and comparator errors);
    :data:`LENS_SIGMA_OF_R0` of the reference radius for a lens (a lens model, Brown's
    set), whose distortion grows with the format."""
    d = camera_defaults(block)
    if isinstance(aps, LensModel):
        r0 = aps.r0 if aps.r0 is not None else d["r0"]
        return LENS_SIGMA_OF_R0 * r0 * 1e3
    if getattr(aps, "name", "") == "brown":  # a lens: its distortion scales with r0
        return LENS_SIGMA_OF_R0 * float(aps.r0) * 1e3
    return AERIAL_AP_SIGMA_UM * d["side"] / AERIAL_FORMAT_MM


def self_calibrate(
    block: Block,
    additional="ebner12",
    *,
    ap_group: ArrayLike | None = None,
    ap_sigma: float | None = None,
    select: bool = True,
    alpha: float = 0.05,
    threshold: float = 0.9,
    keep_t: float | None = None,
    suppress_sigma: float = 1e-3,
    **bundle_options,
) -> SelfCalibration:
    """Self-calibrating bundle adjustment with significance-based parameter selection.

    Parameters
    ----------
    block : Block
        Approximate values and observations (see :func:`bundle_adjust`).
    additional : str or AdditionalParameters or LensModel
        ``"ebner12"``, ``"brown"``, ``"gruen44"`` (sized for the block's camera by
        :func:`default_set`), ``"backward"``, ``"forward"`` (the camera model inside the
        projection, :class:`~orientviz.bundle.LensModel`), or a set object.
    ap_group : array_like of int, shape (m,), optional
        Image → group of the additional parameters (default: one group for all images;
        one per camera for a lens model).
    ap_sigma : float, optional
        σ (µm) of the pseudo-observations p = 0 of kept parameters; default from the
        camera (:func:`default_ap_sigma`: 10 µm for a 23 cm aerial format, scaled with
        the format; a tenth of the reference radius for a lens model).
    select : bool
        Suppress insignificant and over-correlated parameters and adjust again.
    alpha : float
        Significance level of the parameter tests.
    threshold : float
        abs(ρ) above which a pair of parameters counts as over-parameterisation: the
        partner with the smaller t is suppressed — unless its t exceeds ``keep_t``
        (the block determines it despite the correlation; the pair is reported in
        ``correlated``, e.g. K2~K3 of a real lens).
    keep_t : float, optional
        See ``threshold``. Default: 10 for the µm-sets; for a lens model the test's
        critical value — a significant lens term is never dropped for a correlation
        (dropping K2 of a real lens biases K1 and c by tens of σ).
    suppress_sigma : float
        σ (µm) that holds a suppressed parameter at 0.
    **bundle_options
        Passed to :func:`bundle_adjust` (``control``, ``max_iter``, …).

    Raises
    ------
    InputError
        Unknown set name or a non-positive ``ap_sigma``.
    NotDeterminableError
        The set is not determinable by the block; the message names correlated pairs.
    """
    aps = default_set(additional, block) if isinstance(additional, str) else additional
    if keep_t is None:
        from scipy.special import ndtri  # scipy.special loads many modules: only when the rule is asked

        keep_t = float(ndtri(1 - alpha / 2)) if isinstance(aps, LensModel) else 10.0
    if ap_sigma is None:
        ap_sigma = default_ap_sigma(aps, block)
    if not (np.isfinite(ap_sigma) and ap_sigma > 0):
        raise InputError(f"ap_sigma: expected a positive σ in µm, got {ap_sigma}")
    opts = dict(bundle_options, precision=True)
    try:
        first = bundle_adjust(block, additional=aps, ap_group=ap_group, ap_sigma=ap_sigma, **opts)
    except NotDeterminableError as exc:
        raise _explain(block, aps, ap_group, exc, opts) from None
    an = analyse(first, alpha=alpha, threshold=threshold, ap_sigma=ap_sigma)
    if not select:
        return SelfCalibration(first, first, an, an, aps, list(aps.names), [], {})
    reasons: dict[str, str] = {}
    sig_any = {n: False for n in aps.names}
    t_max = {n: 0.0 for n in aps.names}
    for nm, s, t in zip(an.names, an.significant, an.t):
        b = _base(nm)
        sig_any[b] |= bool(s)
        t_max[b] = max(t_max[b], float(t))
    for nm in an.undetermined:
        reasons.setdefault(_base(nm), "not determinable by the block (σ ≈ its pseudo-observation)")
    for b in aps.names:
        if not sig_any[b] and b not in reasons:
            reasons[b] = f"not significant (largest t = {t_max[b]:.1f})"
    correlated: list[str] = []
    for a, b, r in an.pairs:
        weak = min((_base(a), _base(b)), key=lambda n: t_max[n])
        if weak not in reasons and _base(a) != _base(b):
            other = _base(b) if weak == _base(a) else _base(a)
            if t_max[weak] > keep_t:  # determined despite the correlation: kept, reported
                correlated.append(f"{_base(a)}~{_base(b)} ρ = {r:+.2f} (both kept: t > {keep_t:g})")
            else:
                reasons[weak] = f"correlated with {other} (ρ = {r:+.2f})"
    sigma = np.array([suppress_sigma if n in reasons else ap_sigma for n in aps.names])
    final = bundle_adjust(block, additional=aps, ap_group=ap_group, ap_sigma=sigma, **opts)
    kept = [n for n in aps.names if n not in reasons]
    fa = analyse(final, alpha=alpha, threshold=threshold)
    return SelfCalibration(final, first, an, fa, aps, kept, [n for n in reasons], reasons,
                           correlated)  # fmt: skip


def _explain(block, aps, ap_group, exc, opts) -> NotDeterminableError:
    """A NotDeterminableError naming the correlated pairs of a regularised trial run."""
    try:
        trial = bundle_adjust(block, additional=aps, ap_group=ap_group, ap_sigma=1e3, **opts)
        an = analyse(trial, threshold=0.9)
        pairs = ", ".join(f"{a}~{b} (ρ={r:+.3f})" for a, b, r in an.pairs[:6])
    except NotDeterminableError:
        pairs = ""
    msg = f"the additional parameters '{aps.name}' are not determinable by this block"
    msg += f"; correlated: {pairs}" if pairs else f" ({exc})"
    return NotDeterminableError(msg + "; give ap_sigma or a smaller set", list(aps.names))
