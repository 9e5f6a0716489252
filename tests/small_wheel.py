"""The small bladed disk and casing ring the cyclic-symmetry tests share (6 sectors, coarse)."""

from femrub.fem.material import Material

N = 6
TITANIUM = Material(young=110e9, rho=4500.0, poisson=0.3)
STEEL = Material(young=200e9, rho=7800.0, poisson=0.3)
BLADE = dict(code="0012", span=0.03, root_chord=0.015, tip_chord=0.012, twist=20.0, n_sections=3)
#: the disk sector: bore 20 mm, rim 45 mm, 15 mm thick, elements of 15 mm (10 mm at least)
DISK = dict(hub_radius=0.02, rim_radius=0.045, thickness=0.015, h=0.015, h_min=0.01)


def disk_sector():
    """The meshed 6-blade disk sector."""
    from femrub.geometry.bladed_disk import bladed_disk_sector

    d = DISK
    return bladed_disk_sector(
        N, d["hub_radius"], d["rim_radius"], d["thickness"], BLADE, h=d["h"], h_min=d["h_min"]
    )


def scene_tables(**rotor) -> dict:
    """The wheel as the ``geometry``, ``material`` and ``rotor`` tables of a scene (SI), with
    more ``rotor`` keys."""
    d = DISK
    return {
        "geometry": {"kind": "naca", **BLADE, "h": d["h"], "h_min": d["h_min"]},
        "material": {"young": TITANIUM.young, "poisson": TITANIUM.poisson, "density": TITANIUM.rho},
        "rotor": {
            "sectors": N,
            **{k: d[k] for k in ("hub_radius", "rim_radius", "thickness")},
            **rotor,
        },
    }
