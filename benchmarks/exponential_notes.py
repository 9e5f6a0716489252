"""The reading of ``benchmarks/exponential.py``'s tables (docs/performance.md §6): what they
show and what is not met, with the numbers of the measurement they were written for."""

NOTES = """\
Reading. The exponential stepper is exact between contact events (docs/theory.md §4b): its
error is the same at every step size (what remains on the paper case is its distance to the
θ reference), so its cheapest run at a level is its coarsest step. The frictionless runs are
`ok`: the stepper integrates every work and heat of the energy balance on its exact flights
(`steppers/work.py`), so the balance closes to round-off at every step (with friction too:
the tangential work and the "power" heat of held contacts are integrated exactly; those
runs' status is below). That integration is part of `run` with the balance kept, as for
every method here; "exponential, energy off" (in performance/exponential.md) is the same run
without it. A step without event is one compiled product of a matrix stacked once per held
set (the exact flight, its work integrals and the exact gaps and held multipliers on the
event check grid, and the check itself: `exponential_kernels.flight`); the dyadic algebra
(squaring the sub-step flows, composing a flow or its work integrals over any duration,
doubling the integrals' levels) is compiled too. The event search (root finding, part-step
grids), the impulses and the load signals stay in Python.

θ runs each method's best implementation: on the paper case its compiled one-contact blocks
(`steppers/theta_blocks.py`, a few µs per step); on the blade, whose two frictionless
contacts on a moving casing have no compiled θ path, per step in Python, so the blade table
also runs θ's compiled friction blocks on the same model with μ = 1e-9, the fair comparison
there (slightly less accurate per step than the frictionless path: it needs h = 2.5e-7 s for
1 % `u_L2`). The exponential stepper reaches 1 % `u_L2_nodes` at h = 1e-4 s, 5.8× cheaper
than that θ, while θ in Python and Carpenter do not reach 1 % at the steps tried; 1 % `u_L2`
(the interpolant of the output) is not reached at its finest step (1e-5 s: 1.2 %); the tip
temperature target is not met (θ in Python reaches 1 % at h = 1e-4 s in 7 ms).

With its real Coulomb friction (μ = 0.02, "power" heat, every method on that model) every
exponential run is now `ok`: held slides follow their slip, one direction per step fixed on
the step's end slip (docs/theory.md §4b, `steppers/exponential_slide.py`), so Coulomb's
direction check is 2e-10–4e-10 at h >= 5e-5 s and 5.4e-9 at finer steps (one step with an
impact inside it, whose impulse is along the slip at the impact; the fixed casing direction
gave 1.5e-7–8.5e-7, above the verdict's 1e-8), sliding equality <= 3.7e-9, balances at
round-off. The price: each new direction (quantised to 5e-5 rad) rebuilds the held set's
flows, probe rows and work integrals, about one per sliding step at coarse steps and about 50
over the run at 5e-6 s (directions met are kept), and most sliding steps take two passes; the
runs cost 1.7× (h = 1e-4 s) to 2.8× (5e-6 s) those of the fixed direction (0.03 s and
0.076 s in the previous measurement). θ's compiled friction blocks have meanwhile become about
ten times cheaper (1 % tip temperature at h = 5e-6 s in 0.011 s, 1 % displacement at
2.5e-7 s in 0.12 s), so on this blade the exponential stepper is 2.8× cheaper than θ at 1 %
`u_L2_nodes` (within 0.6 % at h = 2e-4 s) but θ is 3.8× cheaper at 1 % tip temperature and
1.9× at 1 % `u_L2`; Carpenter does not reach 1 % at the steps tried (4 % in temperature at
0.2 × its stability limit, 7 s). The 3× target is not met there.

The 3× target is not met on the paper case, at any error, and the cost-floor table says why.
The tip temperature: the exponential stepper reaches 1 % at its coarsest step (its error does
not depend on h: event location, not the step, sets it; without events it is off by 12 % at
h = 1e-4 s and by 0.6–2× at coarser steps), but there its fixed cost alone (constructor; per
held set the sub-step flows, probe rows and work integrals) is 4.9× the whole 3× target, and
its 31 event steps 14×. The paper `u_L2` (h <= 2.5e-4 s, because the error is measured on the
piecewise-linear interpolant of the output): steps without event (20 µs each), recorder and
fixed cost already exceed the 3× target, and its 27 event steps cost more than the target by
themselves. Profiled (cProfile, h = 2.5e-4 s): a step without event is Python around one
compiled product (the load polynomial, packing the inputs, the step-end checks); an event
step (about 0.6 ms) splits into the part-step work integrals (`WorkIntegrals.over`, about a
third), the root search (about four exact-flow evaluations, each composing about 20 dyadic
levels) and the part-step grids and impulses; the fixed cost is mostly the work integrals'
levels. Cut here: the probe rows by doubling on the cached levels (3.5× cheaper: 8.8e-4 to
2.5e-4 s at h = 5e-3 s), no impulse check at a quiet step's end when the grid shows every free
gap clearly open (compiled), the load signals evaluated on the step's nodes at once; the runs
moved within the machine's noise. Reaching 3× would need the whole step loop, event search
included, compiled as θ's blocks are, and a fixed cost five times smaller; not done. A modal
flow does not apply as such (the augmented generator's load chain is nilpotent, not
diagonalisable); fewer dyadic levels would coarsen the event times (exact to 1e-10 h now).
Without event location (`events = false`) the same stepper is cheap but wrong: an end-of-step
impulse only stops the tip mass while the rest of the bar flies through the casing for a
whole step; event location and held contacts are therefore kept. On the free bar impact the
error at fixed mesh does not depend on the Courant number (no dispersion).
"""
