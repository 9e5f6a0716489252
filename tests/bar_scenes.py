"""The paper's bar as scene text, shared by the CLI and reliability tests."""


def bar_scene(name: str = "tiny", n_elements: int = 5, t_end: float = 0.02) -> str:
    """A short bar rub (concentric casing 15 µm, tip force 7 sin(209.4 t) N, h = 1e-4 s)."""
    return f"""
name = "{name}"
[geometry]
kind = "bar"
n_elements = {n_elements}
[contact]
casing = {{ kind = "concentric", clearance = "15 um" }}
heat_coefficient = 3.0
[loads]
tip_force = {{ law = "sin", amplitude = 7.0, frequency = "209.4 rad/s" }}
[scheme]
h = 1e-4
t_end = {t_end!r}
"""
