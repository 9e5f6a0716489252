"""Hand-written text of the performance pages that ``benchmarks/run_all.py`` renders with the
tables of the JSON files (so that ``--render-only`` keeps it): the error measures and the
readings of the 3D costs and of the hard cases. Edit here, not in the rendered pages."""

# ruff: noqa: E501  (Markdown table rows)

COST_3D_NOTES = """\
Box blades (gmsh, vector P2 displacement + P1 temperature, 8 tip contacts, lobed casing,
thermal coupling on), reduced to n_uv = n_θ = 20 (`benchmarks/cost_3d.py`; each size in a
fresh process). The full model is stepped only while its sparse factorisation stays
affordable; above a few 1e4 dofs the reduction is the way to run.

What the costs depend on (on a blade of about 1e5 P2 displacement dofs such as Rotor 37;
each solver is measured on it in [Blade scale](blade-scale.md), `benchmarks/solvers.py`):

1. *Stiffness assembly*: the P2 gradients are integrated with the lowest exact rule (order
   2 on straight tetrahedra, also exact for the P1×P2 coupling), several times cheaper than
   the mass matrix's order-4 rule on the same mesh.
2. *Sparse factorisation* of the 3D stiffness (damping eigen-solve, the reduction's static
   shapes and shift-invert modes): MKL Pardiso where it is installed, several times faster
   than SuperLU at this size. Per-step solves stay on SuperLU (Pardiso's per-call overhead
   dominates a small reduced solve).
3. *Per-step overhead*: one BLAS thread always, chunked post-processing of observations and
   energy.

What dominates: the reduction's static shapes when the frictional heat is spread
over many tip vertices (each is a thermal boundary dof)."""

MEASURES = """\
Errors are measured on the tip of the bar against a reference (section 2):

* **u L2**: time-L2 relative error of the tip displacement,
  `sqrt(∫ (u − u_ref)² dt / ∫ u_ref² dt)`, the coarse solution interpolated linearly onto the
  reference time grid; **u max**: `max |u − u_ref| / max |u_ref|`;
* **T end**: relative error of the tip temperature rise at the end of the window;
* **P phase**: largest error of the impulse of one contact phase (N s, summed over the steps
  of a load period, `2π/Ω` = 30 ms: the paper case has one contact phase per period; the
  impact case has one phase), divided by the largest reference phase impulse;
* **t1**: absolute error (s) of the first-contact time, the end `t_k` of the first step
  carrying an impulse above 1e-6 of the largest one (resolution: one step).

CPU = `time.process_time()` of building the stepper and `run()` with the energy balance on
(what a user runs); the offline cost of a reduction is listed apart."""


HARD_NOTES = """\
### Findings

**Coarse steps (h = 5e-3 s: 6 steps per load period).** The table's ratios are the tip
temperature (T) and the frictional heat (Q) at 0.4 s over their values at h = 1e-6 s with
the default rule; 1/W is the effective mass of the impact law (inverse Delassus operator);
the last share is the part of the impulse given in steps that end with the gap open by
more than 1 µm. The default *position* rule (the contact put on its target gap) gives no
impulse at an open gap at any step; at γ = 1/2 it stays within a factor of two of the fine
step at 6 steps per load period (status `ok`), and with numerical damping (γ > 1/2) the
time-step check flags its runs `inaccurate`. The velocity-level rules
(*paper*, *plain*) activate a contact when the *free* step would end inside the casing;
the impulse then cancels the approach velocity at the end of the step (e = 0), which at
this step size freezes the tip where it was, up to tens of µm away from the casing: no
consistent active set exists (closing leaves the gap open, opening closes it) and the
impulse is kept (`ThetaMethod` docstring). All of their impulse is then given at an open
gap, each impulse is large (a step is quasi-static, ω₁h ≈ 15, so 1/W approaches
(hγ)² EA/L, far above the bar's own mass), the frictional heat α P follows the impulses
and the coupled runs reach the 1500 K stop (a numerical runaway, `diverged-physically`).
The *predicted* (Moreau–Jean) rule tests `g_k + γ h ġ_k`, which at this step almost never
sees the crossing: the tip sits a few µm inside the casing with almost no impulse, and the
*capped* rule lies between. Numerical damping (γ > 1/2) cures none of the velocity-level
rules. At h = 5e-4 s (60 steps per load period) the position and paper rules are within a
few per cent of the fine step in temperature and heat, while their peak force is well
below the fine step's Dirac-like spike: the paper's "large steps underestimate" holds for
the force, not for impulses and heat.

**Stiff heat equation.** With grading 3 the tip elements are tiny (micrometres at 60
elements, tens of nanometres at 200) and their thermal modes are stiff (Carpenter's
explicit limit in the table: nanoseconds or less). With the physical coupling the θ-method
is bounded and converged for both γ_θ = 1/2 and 1 (table: tip temperature within a few per
cent between h = 1e-4 and 2.5e-5 s). The paper's coupling `K^uθ = β K^uu` expands each node
by −β θ whatever its element size, so one hot micrometre-long tip element pushes the tip
tens of µm into a 15 µm gap (and refining makes it worse) while the energy balance closes:
femrub refuses `coupling="paper"` on a graded bar. `gamma_thermal` (γ of the heat rows,
e.g. 1 for backward Euler) is available for stiff heat equations.

**Other cases** (table above). e = 1 without load: the mechanical energy is constant to
round-off over hundreds of impacts; e = 0 and 0.5: no step increases the energy beyond
round-off. α = 7 m/s: every scheme stops `diverged-physically` at the same time with
closed balances. Grazing and chattering: no penetration beyond round-off with the position
rule; the contact work of a step is never positive beyond round-off. Twenty contacts
closing at once: solved in one step each (Lemke). Carpenter 2 % above its stability limit:
blow-up detected after a few dozen steps, status `unstable`, results kept."""
