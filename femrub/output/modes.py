"""Files of ``femrub modes``: the modes table, the coincidence speeds and their figure.

* ``modes.csv``: one row per mode, columns ``structure`` (``disk``, ``casing`` or
  ``blade``), ``nodal_diameter`` (empty for a single blade), ``family`` (1: the lowest
  mode of each nodal diameter), ``frequency_hz`` and ``rotation_speed`` (rad/s, the speed
  of the centrifugal prestress the frequency is at; 0 for the casing); over a list of
  speeds, one block of disk rows per speed.
* ``coincidences.csv``: ``nodal_diameter``, ``disk_family``, ``casing_family``,
  ``rotation_speed`` (rad/s) of ``k Ω = ω_disk + ω_casing``
  (:mod:`femrub.model.coincidence`), with the two frequencies (Hz) and the ``method``
  (``interpolated``, ``outside-range`` or ``scene-speed``).
* ``modes.png``: frequency against nodal diameter, one marker series per family (the
  rotor at speed, or at the top speed of a list, filled, the casing open), and the
  coincidence speeds against nodal diameter beside it.
* ``campbell.png`` (over a list of speeds): the Campbell diagram in the rotating frame.
  Each disk mode ``(k, j)`` is a solid line ``ω_disk,k,j(Ω) / 2π`` coloured by ``k``; each
  casing mode ``(k, j)``, ``k >= 1``, is the dashed line ``(k Ω − ω_casing,k,j) / 2π`` of
  the same colour, the frequency of the casing's forward ``k``-wave seen from the rotor
  (``cos(k θ − ω_c t)`` with ``θ = θ_r + Ω t`` is ``cos(k θ_r + (k Ω − ω_c) t)``, a
  backward wave there). A disk line crosses a dashed line of its colour where
  ``k Ω = ω_disk + ω_casing``: the coincidences, marked.
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
    "plot_campbell",
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
    "method",
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


def write_modes(path, tables) -> None:
    """``modes.csv`` from ``{structure: ModeTable}`` or ``[(structure, ModeTable), ...]``
    (one block of rows per table, in order)."""
    blocks = tables.items() if isinstance(tables, dict) else tables
    with atomic_file(Path(path), "w") as fh:
        w = csv.writer(fh)
        w.writerow(MODES_COLUMNS)
        for structure, table in blocks:
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
                    c.method,
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


def plot_modes(
    path, tables: dict, found, *, rotation_speed: float, speed_range=None, title: str = ""
) -> None:
    """``modes.png``: frequencies by nodal diameter and family; coincidence speeds.

    ``rotation_speed`` (rad/s): the disk table's speed; ``speed_range``: ``(Ω_1, Ω_n)`` of a
    list of speeds, shaded on the coincidence panel (else the scene's speed is drawn)."""
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
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=7, loc="best")
    if two:
        ax = axes[0, 1]
        k = np.array([c.nodal_diameter for c in found])
        speed = np.array([c.rotation_speed for c in found])
        pairs = sorted({(c.disk_family, c.casing_family) for c in found})
        for jd, jc in pairs:
            hit = np.array([(c.disk_family, c.casing_family) == (jd, jc) for c in found])
            ax.plot(k[hit], speed[hit], "D", label=f"disk {jd} + casing {jc}")
        if speed_range is None:
            ax.axhline(rotation_speed, color="0.4", ls=":", label="scene speed")
        else:
            ax.axhspan(*speed_range, color="0.85", label="speeds solved")
        ax.set_yscale("log")
        ax.set_xlabel("nodal diameter k")
        ax.set_ylabel("coincidence speed Ω = (ω_disk + ω_casing)/k (rad/s)")
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=7, loc="best")
    fig.tight_layout()
    with atomic_file(Path(path), "wb") as fh:
        fig.savefig(fh, dpi=120, format="png")
    plt.close(fig)


def _disk_lines(ax, sweep, colour) -> None:
    """``ω_disk,k,j(Ω) / 2π`` (Hz) of every ``(k, j)`` over the speeds of ``sweep``."""
    speeds = np.array([t.rotation_speed for t in sweep])
    hz = np.array([t.frequency_hz for t in sweep])
    first = sweep[0]
    for row, (k, j) in enumerate(zip(first.nodal_diameter, first.family, strict=True)):
        ax.plot(speeds, hz[:, row], "-", marker=".", color=colour(k), lw=1.2 if j == 1 else 0.8)


def _casing_lines(ax, casing, speeds, colour) -> None:
    """``(k Ω − ω_casing,k,j) / 2π`` (Hz): the casing's forward waves in the rotating frame."""
    for k, fc in zip(casing.nodal_diameter, casing.frequency_hz, strict=True):
        if k >= 1:
            ax.plot(speeds, k * speeds / (2 * np.pi) - fc, "--", color=colour(k), lw=0.8)


def plot_campbell(path, sweep, casing, found, title: str = "") -> None:
    """``campbell.png`` (module docstring): the disk's frequencies against Ω in the rotating
    frame, the casing's lines ``k Ω − ω_casing`` and the interpolated coincidences.

    Parameters
    ----------
    sweep : sequence of ModeTable
        The disk's modes at increasing speeds (rad/s).
    casing : ModeTable or None
        The casing's modes (at rest); ``None``: the disk alone.
    found : sequence of Coincidence
        Those with ``method == "interpolated"`` are marked.
    """
    from matplotlib.lines import Line2D

    speeds = np.array([t.rotation_speed for t in sweep])
    ks = np.unique(sweep[0].nodal_diameter)
    many = ks.max() >= 10  # tab10 would repeat: a continuous map, one shade per k

    def colour(k):
        if many:
            return plt.get_cmap("turbo")(0.05 + 0.9 * float(k) / float(ks.max()))
        return plt.get_cmap("tab10")(int(k))

    fig, ax = plt.subplots(figsize=(9, 6))
    _disk_lines(ax, sweep, colour)
    top = 1.15 * max(float(np.max([t.frequency_hz for t in sweep])), 1.0)
    handles = [Line2D([], [], color=colour(k), label=f"k = {k}") for k in ks]
    handles.append(Line2D([], [], color="0.3", ls="-", label="disk ω_disk,k(Ω)"))
    if casing is not None:
        _casing_lines(ax, casing, speeds, colour)
        handles.append(Line2D([], [], color="0.3", ls="--", label="k Ω − ω_casing,k"))
    hits = [c for c in found if c.method == "interpolated"]
    if hits:
        ax.plot(
            [c.rotation_speed for c in hits],
            [c.disk_frequency_hz for c in hits],
            "o",
            mfc="none",
            mec="black",
            ms=9,
        )
        handles.append(
            Line2D([], [], color="black", marker="o", mfc="none", ls="", label="k Ω = ω_d + ω_c")
        )
    if speeds[-1] > speeds[0]:
        ax.set_xlim(speeds[0], speeds[-1])
    ax.set_ylim(0.0, top)
    ax.set_xlabel("rotation speed Ω (rad/s)")
    ax.set_ylabel("frequency in the rotating frame (Hz)")
    ax.set_title(title)
    ax.grid(alpha=0.3)
    ax.legend(handles=handles, fontsize=7, loc="upper left", ncol=2)
    fig.tight_layout()
    with atomic_file(Path(path), "wb") as fh:
        fig.savefig(fh, dpi=120, format="png")
    plt.close(fig)
