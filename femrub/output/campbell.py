"""Campbell diagram figure: natural frequencies and engine-order lines against speed."""

from __future__ import annotations

import math

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

__all__ = ["engine_order_range", "plot_campbell", "draw_campbell"]


def engine_order_range(max_speed: float, max_frequency: float, limit: int = 12) -> range:
    """Engine orders ``k`` whose line ``f = k Ω / 2π`` stays below ``1.1 max_frequency``
    up to 40 % of ``max_speed`` (the readable ones), at most ``limit``."""
    if max_speed <= 0:
        return range(0)
    k_max = math.floor(1.1 * max_frequency * 2 * math.pi / (0.4 * max_speed))
    return range(1, max(1, min(limit, k_max)) + 1)


def draw_campbell(ax, speeds, frequencies, *, engine_orders=None, label_modes=True) -> None:
    """Mode lines (Hz) against speed (rad/s) and engine-order lines on ``ax``."""
    speeds = np.asarray(speeds, dtype=float)
    frequencies = np.asarray(frequencies, dtype=float)
    fmax = float(np.nanmax(frequencies)) if frequencies.size else 1.0
    for j in range(frequencies.shape[1]):
        ax.plot(speeds, frequencies[:, j], lw=1.8, label=f"mode {j + 1}" if label_modes else None)
    top = float(speeds.max()) if speeds.size else 0.0
    orders = engine_order_range(top, fmax) if engine_orders is None else range(1, engine_orders + 1)
    s = np.array([0.0, top])
    for k in orders:
        f = k * s / (2 * np.pi)
        ax.plot(s, f, color="0.6", lw=0.7, ls="--", zorder=0)
        end = min(top, 1.1 * fmax * 2 * np.pi / k)
        ax.annotate(
            f"{k}EO", (end, k * end / (2 * np.pi)), fontsize=7, color="0.4", ha="right", va="bottom"
        )
    ax.set_ylim(0.0, 1.1 * fmax)
    ax.set_xlim(float(speeds.min()), top if top > 0 else 1.0)


def plot_campbell(speeds, frequencies, path, *, engine_orders=None, title="") -> None:
    """Write the Campbell diagram to ``path`` (PNG)."""
    fig, ax = plt.subplots(figsize=(7, 5))
    draw_campbell(ax, speeds, frequencies, engine_orders=engine_orders)
    ax.set_xlabel("rotation speed Ω (rad/s)")
    ax.set_ylabel("natural frequency (Hz)")
    ax.set_title(title)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="upper left")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
