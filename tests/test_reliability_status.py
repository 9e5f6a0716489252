"""Status honesty: runs nobody should trust are not reported as ``ok``
(docs/reliability.md)."""

import json
from dataclasses import replace

import numpy as np
import pytest
from bar_scenes import bar_scene

from femrub.analysis import Carpenter, Penalty, ThetaMethod
from femrub.app import build
from femrub.app.blade import _check_mesh
from femrub.app.cli import main
from femrub.cases.bar import bar_model
from femrub.cases.paper import Run, run_case
from femrub.cases.paper_models import paper_reduced_model
from femrub.geometry import box_blade
from femrub.output.verdict import assess
from femrub.scene import SceneError, load_scene, loads_scene

BAR = bar_scene("bar", 10, 0.4)
#: the command-line runs here are judged by their summary.json: no plots drawn
NO_PLOTS = ["--set", "outputs.plots=false"]


def test_reduced_run_with_an_open_energy_balance_is_inaccurate():
    model = paper_reduced_model("RM2", 3.0, True)
    res = ThetaMethod(model, 1e-4).run(0.4)
    assert res.heat_error() > 0.05  # the heat balance of this reduced model does not close
    assert res.status == "inaccurate" and "heat balance residual" in res.message
    # the same rule, with the tolerance raised, lets it through: one place decides
    again = ThetaMethod(model, 1e-4).run(0.4, tolerances={"energy": 10.0, "heat": 10.0})
    assert again.status == "ok"
    full = ThetaMethod(bar_model(), 1e-4).run(0.4)
    assert full.status == "ok" and full.energy_error() < 1e-9


def test_coarse_step_warns_and_names_the_step_to_use():
    coarse, _ = run_case(Run("coarse", h=1e-3), 0.4)
    assert coarse.warnings and "use scheme.h <= " in coarse.warnings[0]
    h_text = coarse.warnings[0].split("scheme.h <= ")[1].split()[0]
    assert float(h_text) <= 5e-4
    fine, _ = run_case(Run("fine", h=1e-4), 0.4)
    assert fine.warnings == [] and fine.status == "ok"


def test_physical_limits_are_on_without_a_limits_table(tmp_path):
    scene = loads_scene(BAR.replace("heat_coefficient = 3.0", "heat_coefficient = 9.0"))
    built = build(scene)
    assert built.limits == {"tip_temperature": 1500.0, "tip_displacement": pytest.approx(0.03)}
    assert built.report["limits_default"] == ["tip_displacement", "tip_temperature"]
    out = tmp_path / "out"
    (tmp_path / "bar.toml").write_text(
        BAR.replace("heat_coefficient = 3.0", "heat_coefficient = 9.0")
    )
    assert main(["run", str(tmp_path / "bar.toml"), "-o", str(out), "-q", *NO_PLOTS]) == 0
    s = json.loads((out / "summary.json").read_text())
    assert s["status"] == "diverged-physically" and "tip_temperature exceeded 1500" in s["message"]
    # a scene's own limit wins over the default
    mine = build(scene.with_changes({"limits.tip_temperature": 300.0}))
    assert mine.limits["tip_temperature"] == 300.0


def test_coarse_steps_on_the_paper_scene_are_not_silently_ok(tmp_path):
    """h = 5e-3 s: 2 steps per contact episode, inaccurate; h = 1e-3 s warns."""
    out = tmp_path / "h5e-3"
    assert main(["run", "paper", "--set", "scheme.h=5e-3", "-o", str(out), "-q", *NO_PLOTS]) == 0
    s = json.loads((out / "summary.json").read_text())
    assert s["status"] == "inaccurate" and "use scheme.h <= 0.0005 s" in s["message"]
    out = tmp_path / "h1e-3"
    assert main(["run", "paper", "--set", "scheme.h=1e-3", "-o", str(out), "-q", *NO_PLOTS]) == 0
    s = json.loads((out / "summary.json").read_text())
    assert len(s["warnings"]) == 1 and "use scheme.h <= 0.0004 s" in s["warnings"][0]


@pytest.mark.parametrize("scheme", ["carpenter", "penalty"])
def test_restitution_is_refused_by_schemes_that_ignore_it(scheme):
    model = bar_model(restitution=0.9)
    cls = {"carpenter": Carpenter, "penalty": Penalty}[scheme]
    kw = {"stiffness": 1e8} if scheme == "penalty" else {}
    with pytest.raises(ValueError, match="restitution"):
        cls(model, 1e-6, **kw)
    extra = "\nstiffness = 1e8" if scheme == "penalty" else ""
    doc = BAR.replace("[scheme]\n", f'[scheme]\nname = "{scheme}"{extra}\n').replace(
        "heat_coefficient = 3.0", "heat_coefficient = 3.0\nrestitution = 0.9"
    )
    with pytest.raises(SceneError, match="contact.restitution = 0.9"):
        loads_scene(doc)


@pytest.mark.parametrize("scheme", ["theta", "carpenter", "penalty"])
def test_initial_penetration_is_refused_by_every_scheme(scheme):
    model = bar_model(gap=-1e-3)
    cls = {"theta": ThetaMethod, "carpenter": Carpenter, "penalty": Penalty}[scheme]
    kw = {"stiffness": 1e8} if scheme == "penalty" else {}
    with pytest.raises(ValueError, match="initial penetration: contact 0 starts 0.001 m inside"):
        cls(model, 1e-6, **kw)


def test_quoted_numbers_without_unit_are_refused():
    with pytest.raises(SceneError, match=r"contact.casing.clearance.*without a unit.*'15 m'"):
        loads_scene(BAR.replace('clearance = "15 um"', 'clearance = "15"'))


def test_clearance_out_of_scale_with_the_blade_is_refused(tmp_path, capsys):
    (tmp_path / "bar.toml").write_text(BAR.replace('clearance = "15 um"', "clearance = 15"))
    assert main(["check", str(tmp_path / "bar.toml"), "-q"]) == 2
    err = capsys.readouterr().err
    assert "contact.casing.clearance" in err and "times the blade's size" in err


def test_length_unit_slip_on_a_mesh_file_is_refused(tmp_path, capsys):
    mesh = tmp_path / "blade.msh"
    box_blade(0.1, 0.03, 0.003, h=0.01, n_contact=3).save(mesh)
    scene = tmp_path / "mesh.toml"
    scene.write_text(
        f'[geometry]\nkind = "mesh"\npath = "{mesh}"\nlength_unit = "mm"\n'
        '[contact]\ncasing = { kind = "concentric", clearance = "50 um" }\n'
        "[scheme]\nh = 1e-6\nt_end = 1e-5\n"
    )
    assert main(["check", str(scene), "-q"]) == 2
    err = capsys.readouterr().err
    assert "blade's size 0.0001 m" in err and "geometry.length_unit = 'mm'" in err
    scene.write_text(scene.read_text().replace('"mm"', '"m"'))
    assert load_scene(scene)["geometry.length_unit"] == "m"


def test_repeated_contact_nodes_and_duplicate_mesh_nodes_are_refused(tmp_path, capsys):
    blade = box_blade(0.1, 0.03, 0.003, h=0.01, n_contact=3)
    mesh = tmp_path / "blade.msh"
    blade.save(mesh)
    scene = tmp_path / "mesh.toml"
    nodes = (
        [int(n) for n in blade.vertex_ids[blade.node_sets["tip"][:2]]]
        if (blade.vertex_ids is not None)
        else [1, 2]
    )
    scene.write_text(
        f'[geometry]\nkind = "mesh"\npath = "{mesh}"\n'
        f"[contact]\nnodes = [{nodes[0]}, {nodes[1]}, {nodes[0]}]\n"
        'casing = { kind = "concentric", clearance = "50 um" }\n'
        "[scheme]\nh = 1e-6\nt_end = 1e-5\n"
    )
    assert main(["check", str(scene), "-q"]) == 2
    assert "listed twice" in capsys.readouterr().err
    # a mesh with a duplicated node (same coordinates, two node numbers)
    m = blade.mesh
    p = np.hstack([m.p, m.p[:, :1]])
    t = m.t.copy()
    t[t == 0] = p.shape[1] - 1
    t[0, 0] = 0  # one element keeps the original node: two nodes at one point
    dup = replace(blade, mesh=type(m)(p, t))
    with pytest.raises(SceneError, match="degenerate mesh.*1 duplicate node"):
        _check_mesh(None, dup)


def test_assess_is_the_one_place_that_decides():
    res = ThetaMethod(bar_model(), 1e-4).run(0.01)
    res.energy["energy_error"] = res.energy["energy_error"] + 1.0  # an open balance
    assess(res)
    assert res.status == "inaccurate"


def test_every_failed_check_is_named_in_the_message():
    res = ThetaMethod(bar_model(), 1e-4).run(0.01)
    tol = {
        "reduction": {"estimate": 0.06, "tolerance": 0.05},
        "time_step": {"estimate": 0.19, "tolerance": 0.05, "h": 1e-4},
    }
    assess(res, tolerances=tol)
    assert res.status == "inaccurate"
    first, second = res.message.split("; ")
    assert first.startswith("estimated reduction error 6 %")
    assert second.startswith("estimated time-step error 19 %")
    one = ThetaMethod(bar_model(), 1e-4).run(0.01)
    assess(one, tolerances={"reduction": {"estimate": 0.06, "tolerance": 0.05}})
    assert "; " not in one.message and "reduction error" in one.message
