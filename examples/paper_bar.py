"""The paper's 20-node thermoelastic bar rubbing the casing (Thorin et al. 2018, Sec. 4).

Coupled vs uncoupled model with the θ-method (h = 1e-4 s, γ = 1/2) and Carpenter's scheme
(h = 1e-5 s), over 0.4 s. Run: ``python examples/paper_bar.py``; results are module-level
names that the tests import.
"""

import femrub as fr

ALPHA = 3.0  # m/s, frictional heat f_tip = α λ
T_END = 0.4

coupled = fr.bar_model(alpha=ALPHA)
uncoupled = fr.bar_model(alpha=ALPHA, coupling="none")

theta = fr.ThetaMethod(coupled, h=1e-4).run(T_END)
theta_uncoupled = fr.ThetaMethod(uncoupled, h=1e-4).run(T_END)
carpenter = fr.Carpenter(coupled, h=1e-5).run(T_END)
carpenter_limit = fr.Carpenter(coupled, h=1e-5).stability_limit()

first_contact_time = theta.first_contact_time()
tip_temperature_end = theta.signal("tip_temperature")[-1]

if __name__ == "__main__":
    for name, r in [
        ("θ coupled", theta),
        ("θ uncoupled", theta_uncoupled),
        ("Carpenter", carpenter),
    ]:
        print(
            f"{name:12s} status={r.status} first contact={r.first_contact_time():.5f} s "
            f"T_tip(end)={r.signal('tip_temperature')[-1]:.2f} K "
            f"max force={r.force.max():.2f} N  cpu={r.cpu_seconds:.2f} s"
        )
    print(f"Carpenter stability limit: {carpenter_limit:.3g} s")
