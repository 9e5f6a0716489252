"""Casing outputs of a run: wear map (CSV, PNG), wear history, casing temperatures."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from .jsonfile import read_json, write_json  # noqa: E402

__all__ = ["write_casing_heat", "write_wear"]


def write_wear(wear, out) -> dict:
    """Write ``wear_map.csv``, ``wear_map.png`` and ``wear_history.csv`` into ``out``, add
    ``max_wear_depth`` (m), ``worn_volume`` (m³) and ``max_incursion`` (m: the deepest any
    contact reached below the unworn surface, :attr:`Abradable.incursion
    <femrub.contact.abradable.Abradable.incursion>`) to ``out/summary.json``; return them.

    ``wear_map.csv``: one row per casing-angle cell (``angle_deg`` = its centre), one column
    per axial cell (``z=<centre in m>``): the worn surface's depth at the cell centres
    (:attr:`~femrub.contact.abradable.Abradable.surface`), in m. ``wear_history.csv``: ``t_s``,
    ``max_wear_depth_m`` at the start and at every step that removed coating.
    """
    out = Path(out)
    surface = wear.surface
    ang = np.degrees(wear.angle_centres())
    z = wear.axial_centres()
    header = "angle_deg," + ",".join(f"z={v:.6g}" for v in z)
    np.savetxt(
        out / "wear_map.csv",
        np.column_stack([ang, surface]),
        delimiter=",",
        header=header,
        comments="",
        fmt="%.8g",
    )
    hist = np.array(wear.history, dtype=float)
    np.savetxt(
        out / "wear_history.csv",
        hist,
        delimiter=",",
        header="t_s,max_wear_depth_m",
        comments="",
        fmt="%.8g",
    )
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(11, 4), gridspec_kw={"width_ratios": [3, 2]})
    edges = np.degrees(np.linspace(0, 2 * np.pi, wear.n_angle + 1))
    im = ax.pcolormesh(edges, wear.z_edges * 1e3, surface.T * 1e6, shading="flat", cmap="magma_r")
    fig.colorbar(im, ax=ax, label="wear depth (µm)")
    axial = wear.grid.axial  # where the contacts cut
    for i, z_i in enumerate(np.unique(np.round(axial, 12))):
        ax.axhline(z_i * 1e3, color="c", lw=0.5, ls="--", label="contacts" if i == 0 else None)
    if axial.size:
        ax.legend(loc="upper right", fontsize=7)
    ax.set_xlabel("casing angle (deg)")
    ax.set_ylabel("axial position (mm)")
    ax.set_title(f"wear map (coating {wear.thickness * 1e6:.4g} µm)")
    bx.step(hist[:, 0], hist[:, 1] * 1e6, where="post")
    bx.set_xlabel("time (s)")
    bx.set_ylabel("largest wear depth (µm)")
    bx.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(out / "wear_map.png", dpi=110)
    plt.close(fig)
    keys = {
        "max_wear_depth": wear.max_depth,
        "worn_volume": wear.worn_volume,
        "max_incursion": float(np.clip(wear.incursion, 0.0, None).max(initial=0.0)),
    }
    _add_to_summary(out / "summary.json", keys)
    return keys


def write_casing_heat(heat, t_end: float, out) -> dict:
    """Write ``casing_temperature.csv`` (wall temperature rise per cell at ``t_end``, laid out
    as ``wear_map.csv``) and add ``max_casing_temperature`` (K) and ``casing_heat_in`` (J)
    to ``out/summary.json``; return them."""
    out = Path(out)
    grid = heat.grid
    T = heat.map_at(t_end)
    header = "angle_deg," + ",".join(f"z={v:.6g}" for v in grid.axial_centres())
    table = np.column_stack([np.degrees(grid.angle_centres()), T])
    np.savetxt(
        out / "casing_temperature.csv", table, delimiter=",", header=header, comments="", fmt="%.8g"
    )
    hist = np.array(heat.history, dtype=float)
    keys = {
        "max_casing_temperature": float(hist[:, 1].max()),
        "casing_heat_in": heat.heat_in,
    }
    _add_to_summary(out / "summary.json", keys)
    return keys


def _add_to_summary(path: Path, keys: dict) -> None:
    """Add ``keys`` to an existing ``summary.json`` (written whole, as every summary is)."""
    if path.exists():
        write_json(path, {**read_json(path), **keys})
