"""Monotone conduction operator (femrub.fem.monotone): no temperature below
ambient without a sink on the twisted NACA mesh (the built-in scene's choice), the Galerkin
default and the paper bar's matrix unchanged."""

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from femrub.app.blade import load_blade
from femrub.app.translate import material_of
from femrub.cases.bar import PAPER, _bar_parts
from femrub.contact.points import locate_contacts
from femrub.fem.discretisation import assemble, discretise
from femrub.fem.monotone import conduction_operator, monotone, positive_couplings
from femrub.scene.scene import load_scene


@pytest.fixture(scope="module")
def naca():
    scene = load_scene("twisted-naca")
    disc = discretise(load_blade(scene), 2)
    return disc, material_of(scene, None, [])


def _heated(disc, mats, h=2e-4, steps=100):
    """Backward Euler on C θ' + K θ = q, q a unit heat rate into the outermost tip contact."""
    pts = locate_contacts(disc)
    q = pts.heat[int(np.argmax(pts.radii))].toarray().ravel()[mats.free_t]
    C, K = mats.Ctt, mats.Ktt
    lu = spla.splu(sp.csc_matrix(C / h + K))
    theta, low = np.zeros(mats.n_t), 0.0
    for _ in range(steps):
        theta = lu.solve(C @ theta / h + q)
        low = min(low, theta.min())
    return low, theta.max()


def test_operator_is_a_conservative_symmetric_m_matrix(naca):
    disc, material = naca
    K = assemble(disc, material, conduction="galerkin").Ktt
    assert positive_couplings(K) > 0  # obtuse tetrahedra: the premise of the fix
    L = monotone(K)
    assert positive_couplings(L) == 0
    assert abs(L - L.T).max() <= abs(K - K.T).max() + 1e-14 * abs(K).max()
    np.testing.assert_allclose(L.sum(axis=1), K.sum(axis=1), atol=1e-12 * abs(K).max())
    D = (L - K).toarray()  # the added diffusion is a graph Laplacian: PSD
    assert np.linalg.eigvalsh(D).min() > -1e-12 * np.abs(D).max()
    with pytest.raises(ValueError, match="galerkin"):
        conduction_operator(K, "upwind")


def test_twisted_naca_heat_has_no_undershoot(naca):
    """The built-in scene's monotone conduction stays >= 0; the Galerkin matrix (the
    default) of the same mesh goes below ambient with a lumped capacity and backward Euler
    (so not the time scheme)."""
    disc, material = naca
    assert load_scene("twisted-naca")["physics"]["conduction"] == "monotone"
    mono = assemble(disc, material, conduction="monotone")
    low, high = _heated(disc, mono)
    assert low >= -1e-12 * high
    galerkin = assemble(disc, material)
    assert galerkin.info["conduction"] == "galerkin"
    low_g, high_g = _heated(disc, galerkin)
    assert low_g < -1e-4 * high_g
    assert abs(high - high_g) < 0.05 * high_g  # hottest vertex barely moves


def test_paper_bar_conduction_unchanged():
    """The 1D bar keeps the Galerkin matrix (an M-matrix already: monotone would be identical)."""
    disc, mats = _bar_parts(PAPER)[:2]
    assert mats.info["conduction"] == "galerkin"
    assert positive_couplings(mats.Ktt) == 0
    assert abs(monotone(mats.Ktt) - mats.Ktt).max() == 0.0
