"""Files of ``femrub modes``: the modes table, the coincidence speeds and their figure.

* ``modes.csv``: one row per mode, columns ``structure`` (``disk``, ``casing`` or
  ``blade``), ``nodal_diameter`` (empty for a single blade), ``family`` (1: the lowest
  mode of each nodal diameter), ``frequency_hz`` and ``rotation_speed`` (rad/s, the speed
  of the centrifugal prestress the frequency is at; 0 for the casing).
* ``coincidences.csv``: ``nodal_diameter``, ``disk_family``, ``casing_family``,
  ``rotation_speed`` (rad/s) of ``k Ω = ω_disk + ω_casing``
  (:mod:`femrub.model.coincidence`), with the two frequencies (Hz).
* ``modes.png``: frequency against nodal diameter, one marker series per family (the
  rotor at speed filled, the casing open), and the coincidence speeds against nodal
  diameter beside it.
"""

from __future__ import annotations

import csv
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from .safe_write import atomic_file  # noqa: E402

__all__ = [
    "MODES_COLUMNS",
    "COINCIDENCE_COLUMNS",
    "plot_modes",
    "write_coincidences",
    "write_modes",
]

MODES_COLUMNS = ("structure", "nodal_diameter", "family", "frequency_hz", "rotation_speed")
COINCIDENCE_COLUMNS = (
    "nodal_diameter",
    "disk_family",
    "casing_family",
    "rotation_speed",
    "disk_frequency_hz",
    "casing_frequency_hz",
)


def _table_rows(structure: str, table) -> list[list]:
    if table.nodal_diameter is None:
        nd = [""] * table.family.size
    else:
        nd = [int(k) for k in table.nodal_diameter]
    return [
        [structure, k, int(j), f"{f:.10g}", f"{table.rotation_speed:.10g}"]
        for k, j, f in zip(nd, table.family, table.frequency_hz, strict=True)
    ]


def write_modes(path, tables: dict) -> None:
    """``modes.csv`` from ``{structure: ModeTable}``."""
    with atomic_file(Path(path), "w") as fh:
        w = csv.writer(fh)
        w.writerow(MODES_COLUMNS)
        for structure, table in tables.items():
            w.writerows(_table_rows(structure, table))


def write_coincidences(path, found) -> None:
    """``coincidences.csv`` from a list of :class:`~femrub.model.coincidence.Coincidence`."""
    with atomic_file(Path(path), "w") as fh:
        w = csv.writer(fh)
        w.writerow(COINCIDENCE_COLUMNS)
        for c in found:
            w.writerow(
                [
                    c.nodal_diameter,
                    c.disk_family,
                    c.casing_family,
                    f"{c.rotation_speed:.10g}",
                    f"{c.disk_frequency_hz:.10g}",
                    f"{c.casing_frequency_hz:.10g}",
                ]
            )


def _families(ax, table, label: str, filled: bool) -> None:
    k = np.zeros(table.family.size) if table.nodal_diameter is None else table.nodal_diameter
    for j in np.unique(table.family):
        hit = table.family == j
        style = {} if filled else {"markerfacecolor": "none"}
        ax.plot(
            k[hit],
            table.frequency_hz[hit],
            "o-" if filled else "s--",
            label=f"{label} {j}",
            **style,
        )


def plot_modes(path, tables: dict, found, *, rotation_speed: float, title: str = "") -> None:
    """``modes.png``: frequencies by nodal diameter and family; coincidence speeds."""
    two = bool(found)
    fig, axes = plt.subplots(1, 2 if two else 1, figsize=(12 if two else 7, 5), squeeze=False)
    ax = axes[0, 0]
    for structure, table in tables.items():
        name = structure if structure != "disk" else f"disk at {rotation_speed:.4g} rad/s, family"
        _families(
            ax, table, name if structure == "disk" else f"{structure} family", structure != "casing"
        )
    ax.set_xlabel("nodal diameter k")
    ax.set_ylabel("natural frequency (Hz)")
    ax.set_title(title)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="best")
    if two:
        ax = axes[0, 1]
        k = np.array([c.nodal_diameter for c in found])
        speed = np.array([c.rotation_speed for c in found])
        pairs = sorted({(c.disk_family, c.casing_family) for c in found})
        for jd, jc in pairs:
            hit = np.array([(c.disk_family, c.casing_family) == (jd, jc) for c in found])
            ax.plot(k[hit], speed[hit], "D", label=f"disk {jd} + casing {jc}")
        ax.axhline(rotation_speed, color="0.4", ls=":", label="scene speed")
        ax.set_yscale("log")
        ax.set_xlabel("nodal diameter k")
        ax.set_ylabel("coincidence speed Ω = (ω_disk + ω_casing)/k (rad/s)")
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=7, loc="best")
    fig.tight_layout()
    with atomic_file(Path(path), "wb") as fh:
        fig.savefig(fh, dpi=120, format="png")
    plt.close(fig)
