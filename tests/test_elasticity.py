"""The batched isotropic stiffness (:mod:`femrub.fem.elasticity`) is scikit-fem's form.

Against ``forms.stiffness.assemble`` on P1 and P2 tetrahedra (straight and curved, the
isoparametric mapping of meshes read with quadratic geometry) and on the 1D bar.
"""

import numpy as np
import pytest
import skfem as fem

from femrub.fem import forms
from femrub.fem.elasticity import isotropic_stiffness
from femrub.fem.forms import lame_parameters

LAM, MU = lame_parameters(110e9, 0.31, 3)


def _same(basis, lam=LAM, mu=MU, area=1.0):
    ref = forms.stiffness.assemble(basis, lam=lam, mu=mu, area=area)
    got = isotropic_stiffness(basis, lam, mu, area)
    assert got.shape == ref.shape
    assert abs(got - ref).max() <= 1e-13 * abs(ref).max()
    return got


@pytest.mark.parametrize("element", [fem.ElementTetP1, fem.ElementTetP2])
def test_tetrahedra(element):
    mesh = fem.MeshTet.init_tensor(
        np.linspace(0, 0.1, 4), np.linspace(0, 0.03, 3), np.linspace(0, 0.005, 3)
    )
    _same(fem.Basis(mesh, fem.ElementVector(element()), intorder=2))


def test_curved_p2_tetrahedra_and_batches(monkeypatch):
    mesh = fem.MeshTet.init_tensor(*(np.linspace(0, 1, 4),) * 3)
    mid = 0.5 * (mesh.p[:, mesh.edges[0]] + mesh.p[:, mesh.edges[1]])
    mid += 0.02 * np.random.default_rng(0).standard_normal(mid.shape)  # curved edges
    mapping = fem.MeshTet2(np.hstack([mesh.p, mid]), mesh.t)._mapping()
    basis = fem.Basis(mesh, fem.ElementVector(fem.ElementTetP2()), mapping=mapping, intorder=3)
    whole = _same(basis)
    import femrub.fem.elasticity as el

    monkeypatch.setattr(el, "BATCH", 7)  # many element batches, a short last one
    assert abs(_same(basis) - whole).max() == 0.0


def test_bar_and_bad_basis():
    mesh = fem.MeshLine(np.linspace(0.0, 1.0, 9))
    K = _same(fem.Basis(mesh, fem.ElementVector(fem.ElementLineP1())), 0.0, 105e9, 2e-4)
    h = 1.0 / 8
    assert K[3, 3] == pytest.approx(2 * (2 * 105e9) * 2e-4 / h, rel=1e-12)  # 2 E A / h, E = 2 μ
    with pytest.raises(ValueError, match="vector"):
        isotropic_stiffness(fem.Basis(mesh, fem.ElementLineP1()), 0.0, 1.0)
