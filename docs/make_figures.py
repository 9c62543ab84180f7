"""Regenerate the figures of the docs pages: ``python docs/make_figures.py``.

Writes docs/figures/conventions.png with :func:`orientviz.plot.conventions.plot_conventions`.
"""

from __future__ import annotations

import pathlib

import matplotlib

matplotlib.use("Agg")

from orientviz.plot.conventions import plot_conventions  # noqa: E402

OUT = pathlib.Path(__file__).resolve().parent / "figures"


def main() -> None:
    OUT.mkdir(exist_ok=True)
    fig = plot_conventions()
    fig.savefig(OUT / "conventions.png", dpi=110, bbox_inches="tight")
    print(f"wrote {OUT / 'conventions.png'}")


if __name__ == "__main__":
    main()
