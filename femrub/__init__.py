"""femrub: finite elements for nonsmooth thermomechanical blade–casing rub.

SI units throughout (m, kg, s, K, N, W, J, Pa). ``import femrub as fr`` gives the user-level
objects of each stage of the pipeline (``docs/architecture.md``):

* scenes: :func:`load_scene`, :func:`loads_scene`, :class:`Scene`, :class:`SceneError`,
  :func:`builtin_scenes`;
* simulations and run folders: :class:`Simulation`, :func:`build`, :func:`run_scene`,
  :func:`run_to_folder`, :func:`folder_status`, :func:`run_sweep`,
  :func:`continue_branch` (periodic orbits);
* blades, meshes and casings: :class:`BladeMesh`, :class:`MeshSize`, :func:`box_blade`,
  :func:`naca_blade`, :func:`sections_blade`, :func:`read_mesh`, :func:`read_rotor37_mesh`,
  :func:`casing_profile`, :class:`Concentric`, :class:`Lobed`, :class:`TwoLobePiollet`;
* bladed disks and casing rings: :func:`bladed_disk_sector`, :func:`casing_ring_sector`,
  :func:`full_wheel`, :func:`cyclic_structure`, :func:`mode_table` (modes by nodal
  diameter), :func:`mode_tables_over_speeds`, :func:`coincidences` (``k Ω = ω_disk +
  ω_casing``), :func:`coincidences_over_speeds`;
* models: :func:`bar_model`, :func:`solid_model`, :func:`build_rub` with :class:`RubConfig`,
  :func:`first_order_model`, :class:`FirstOrderModel` (Eqs. 8-9) and their parts;
* reduction: :class:`ThermoelasticCraigBampton` (``reduce(n_uv, n_theta)``, Eqs. 10-15),
  :func:`craig_bampton_thermal`;
* steppers: :class:`ThetaMethod`, :class:`Carpenter`, :class:`Penalty`,
  :class:`ExponentialMoreau`, :func:`make_stepper` (each with ``run(t_end, options)``),
  :class:`RunOptions`;
* results: :class:`Results`, :func:`load_results`.

Every name is imported on first use (PEP 562), so ``import femrub`` and ``femrub --help``
stay fast.
"""

from ._lazy import lazy_attributes

__version__ = "0.1.0"

# name -> the module that defines it, imported on first access
_LAZY = {
    # scenes
    "Scene": ".scene.scene",
    "builtin_scenes": ".scene.scene",
    "load_scene": ".scene.scene",
    "loads_scene": ".scene.scene",
    "SceneError": ".scene.spec",
    "rpm": ".scene.units",
    # simulations and run folders
    "Simulation": ".app.simulation",
    "build": ".app.simulation",
    "run_scene": ".app.run",
    "run_sweep": ".app.sweep",
    "continue_branch": ".periodic.continuation",
    "folder_status": ".output.folder",
    "run_to_folder": ".output.run_folder",
    # blades, meshes and casings
    "BladeMesh": ".geometry.blade_mesh",
    "MeshSize": ".geometry.mesh_size",
    "box_blade": ".geometry.box_blade",
    "naca_blade": ".geometry.naca_blade",
    "sections_blade": ".geometry.section_blade",
    "read_mesh": ".geometry.readers",
    "read_rotor37_mesh": ".geometry.rotor37",
    "casing_profile": ".contact.casing",
    "Concentric": ".contact.casing",
    "Lobed": ".contact.casing",
    "TwoLobePiollet": ".contact.casing",
    # bladed disks and casing rings: cyclic sectors, modes by nodal diameter
    "bladed_disk_sector": ".geometry.bladed_disk",
    "casing_ring_sector": ".geometry.casing_ring",
    "full_wheel": ".geometry.cyclic_sector",
    "cyclic_structure": ".model.cyclic",
    "mode_table": ".model.cyclic",
    "mode_tables_over_speeds": ".model.cyclic",
    "coincidences": ".model.coincidence",
    "coincidences_over_speeds": ".model.coincidence",
    # models
    "PAPER": ".cases.bar",
    "BarCase": ".cases.bar",
    "bar_config": ".cases.bar",
    "bar_matrices": ".cases.bar",
    "bar_model": ".cases.bar",
    "solid_model": ".model.rub",
    "ContactConfig": ".model.config",
    "RubConfig": ".model.config",
    "build_rub": ".model.builder",
    "ThermoelasticMatrices": ".fem.assembly",
    "assemble_thermoelastic": ".fem.assembly",
    "Material": ".fem.material",
    "ContactSpec": ".model.build",
    "Load": ".model.build",
    "first_order_model": ".model.build",
    "Contact": ".model.first_order",
    "EnergyForms": ".model.first_order",
    "FirstOrderModel": ".model.first_order",
    "Layout": ".model.first_order",
    "LoadTerm": ".model.first_order",
    # reduction
    "ThermoelasticCraigBampton": ".reduction.craig_bampton",
    "craig_bampton_thermal": ".reduction.craig_bampton",
    # steppers
    "Carpenter": ".analysis.steppers",
    "Penalty": ".analysis.steppers",
    "ExponentialMoreau": ".analysis.steppers",
    "ThetaMethod": ".analysis.steppers",
    "make_stepper": ".analysis.steppers",
    "RunOptions": ".analysis.options",
    # results
    "Results": ".output.results",
    "load_results": ".output.load",
}

__all__ = sorted(_LAZY)


__getattr__, __dir__ = lazy_attributes(__name__, _LAZY, __all__)
