"""Built-in viewer demos: ``block``, ``pair`` and ``radar`` (``orientviz view DEMO``).

* ``block`` — a simulated block (:func:`orientviz.simulate.simulate_block`) with
  gross errors (blunders) and systematic image errors (Ackermann's ~10 µm,
  :func:`orientviz.simulate.systematic.typical`); its truth drives the deformation view.
* ``pair`` — a stereo pair with Kovarik's camera (c = 152.7 mm, 23 × 23 cm) whose right
  image is slightly misoriented: the y-parallax arrows show the gaps between the rays.
* ``radar`` — Geier's radar panorama geometry: stations, range spheres, projection
  circles and the two trilateration candidates.

A :class:`~orientviz.viewer.demo.Demo` bundles the state for the block panel with an optional ``extra``
builder for content beyond a block (parallax arrows, radar spheres).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from ..adjust import Adjustment
from ..block import Block
from ..errors import InputError
from .demo import Demo
from .state import BlockState

#: default seed of the demos (deterministic scenes)
SEED = 7


def demo_from_block(block: Block, result: Adjustment | None = None, title: str = "Block") -> Demo:
    """A demo showing ``block`` (start values), or its adjustment ``result``."""
    return Demo(
        "block",
        title,
        block.summary(),
        BlockState(block, result),
    )


def block_demo(
    rng: np.random.Generator | int = SEED, strips: int = 3, images_per_strip: int = 8
) -> Demo:
    """A simulated block with blunders and systematic image errors."""
    from ..simulate import simulate_block  # a demo's own stack: not for a problem file
    from ..simulate.systematic import typical  # a demo's own stack: not for a problem file
    from .deformation import deformation_extra  # a demo's own stack: not for a problem file

    sim = simulate_block(
        strips,
        images_per_strip,
        rng=rng,
        gross={"count": 4, "size_mm": 0.04},
        systematic=typical(10.0),
    )
    state = BlockState(sim.block)
    gross = sim.info.get("gross", {})
    n_gross = len(gross.get("index", [])) if isinstance(gross, dict) else 0
    desc = (
        f"{sim.block.summary()}. Simulated with {n_gross} blunders (40 µm) and systematic "
        "image errors of about 10 µm. Press *run to convergence*, then look at the largest "
        "residuals, *colour by quality* and the worst images; switch a ray or an image off "
        "under *act on the adjustment* (undo / rewind in the list of changes); *reset* "
        "starts again from the approximate values."
    )
    return Demo(
        "block", "Simulated block", desc, state,
        deformation_extra(state, sim.truth, _systematic_twin(sim, rng, strips, images_per_strip)),
    )  # fmt: skip


def _systematic_twin(sim: Any, rng: Any, strips: int, images_per_strip: int) -> Block | None:
    """The demo block's observations with only their systematic errors (the same seed
    without random errors and blunders; σ as in the demo), or None for a Generator seed."""
    from ..simulate import simulate_block  # a demo's own stack: not for a problem file
    from ..simulate.systematic import typical  # a demo's own stack: not for a problem file

    if not isinstance(rng, int | np.integer):
        return None
    twin = simulate_block(
        strips, images_per_strip, rng=rng, sigma_image_mm=0.0, systematic=typical(10.0)
    )
    b = twin.block
    if b.n_observations != sim.block.n_observations or not np.allclose(
        twin.truth.points.xyz, sim.truth.points.xyz
    ):
        return None
    b.observations.sigma = sim.block.observations.sigma.copy()
    return b


def pair_demo(rng: np.random.Generator | int = SEED) -> Demo:
    """A stereo pair with y-parallaxes (Kovarik's camera, right image misoriented)."""
    from .pair_scene import pair_demo as build_pair  # a demo's own stack: not for a problem file

    return build_pair(rng)


def radar_demo() -> Demo:
    """Geier's radar panorama test geometry."""
    from .radar_scene import radar_demo as build_radar  # a demo's own stack: not for a file

    return build_radar()


def design_demo(studio: Any = None) -> Demo:
    """The design studio on ``studio`` (a :class:`~orientviz.viewer.studio.Studio`;
    default: its first design): plan a block, see its precision and reliability live."""
    from .studio_panel import DESCRIPTION, StudioView  # the studio: loaded for its demo only

    if studio is None:
        from .studio import Studio  # the design studio: loaded for its demo only

        studio = Studio()
    title = "Block design studio" + (f": {studio.title}" if studio.title else "")
    return Demo("design", title, DESCRIPTION, None, lambda app: StudioView(app, studio).build())


def design_from_file(target: str) -> Demo:
    """The design studio on the geometry of a block problem file or data set."""
    from .studio import Studio  # the design studio: loaded for its demo only

    return design_demo(Studio.from_file(target))


#: demo name → builder
DEMOS: dict[str, Callable[[], Demo]] = {
    "block": block_demo,
    "pair": pair_demo,
    "radar": radar_demo,
    "design": design_demo,
}


def load_demo(name: str) -> Demo:
    """Build demo ``name`` (``block``, ``pair`` or ``radar``)."""
    if name not in DEMOS:
        raise InputError(f"unknown demo {name!r}; available: {', '.join(DEMOS)}")
    return DEMOS[name]()
