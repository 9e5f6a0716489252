"""The CalculiX files the validation benchmarks read (``benchmarks/_calculix.py``): the
eigenvalue table of a ``.dat``, the matrices of a matrix-storage step, and the input built
from a deck. The runs of ``ccx`` itself skip when it is not installed."""

import numpy as np
import pytest
import scipy.linalg as sla

DAT = """

     E I G E N V A L U E   O U T P U T

 MODE NO    EIGENVALUE                       FREQUENCY
                                     REAL PART            IMAGINARY PART
                           (RAD/TIME)      (CYCLES/TIME     (RAD/TIME)

      1   0.3846011E+07   0.1961125E+04   0.3121227E+03   0.0000000E+00
      2   0.3361869E+08   0.5798162E+04   0.9228062E+03   0.0000000E+00
      3   0.5363833E+08   0.7323819E+04   0.1165622E+04   0.0000000E+00

     P A R T I C I P A T I O N   F A C T O R S

MODE NO.   X-COMPONENT     Y-COMPONENT     Z-COMPONENT     X-ROTATION

      1  -0.1401846E-02   0.1509497E-01   0.1684550E-01  -0.7191372E-01
"""


@pytest.fixture(scope="module")
def ccx_io(load_benchmark):
    return load_benchmark("_calculix")


def test_dat_reader_takes_the_eigenvalue_table_only(ccx_io, tmp_path):
    path = tmp_path / "job.dat"
    path.write_text(DAT)
    table = ccx_io.read_frequencies(path)
    assert list(table["mode"]) == [1, 2, 3]
    np.testing.assert_allclose(table["frequency_hz"], [312.1227, 922.8062, 1165.622])
    np.testing.assert_allclose(table["omega"], 2 * np.pi * table["frequency_hz"], rtol=1e-6)
    np.testing.assert_allclose(table["eigenvalue"], table["omega"] ** 2, rtol=1e-6)


def test_dat_reader_refuses_a_file_without_frequencies(ccx_io, tmp_path):
    path = tmp_path / "static.dat"
    path.write_text(" displacements (vx,vy,vz) for set NALL and time  0.1000000E+01\n")
    with pytest.raises(ValueError, match="no eigenvalue table"):
        ccx_io.read_frequencies(path)


def _cantilever(n: int = 4) -> str:
    """A steel beam of ``n`` C3D8 bricks (10 × 10 × 10 mm each) clamped at x = 0 (N-mm-t-s)."""
    nodes, number = [], {}
    for i in range(n + 1):
        for j, (y, z) in enumerate(((0, 0), (10, 0), (10, 10), (0, 10))):
            number[i, j] = len(nodes) + 1
            nodes.append(f"{number[i, j]}, {10.0 * i}, {y}, {z}")
    bricks = [
        ", ".join(
            str(number[i + s, j]) for s, js in ((0, (0, 1, 2, 3)), (1, (0, 1, 2, 3))) for j in js
        )
        for i in range(n)
    ]
    bricks = [f"{e + 1}, {b}" for e, b in enumerate(bricks)]
    root = "\n".join(f"{number[0, j]}, 1, 3" for j in range(4))
    return "\n".join(
        [
            "*NODE, NSET=Nall",
            *nodes,
            "*ELEMENT, TYPE=C3D8, ELSET=Eall",
            *bricks,
            "*BOUNDARY",
            root,
            "*MATERIAL, NAME=STEEL",
            "*ELASTIC",
            "210000., 0.3",
            "*DENSITY",
            "7.8e-9",
            "*SOLID SECTION, ELSET=Eall, MATERIAL=STEEL",
            "*STEP",
            "*STATIC",
            "*END STEP",
        ]
    )


@pytest.fixture(scope="module")
def cantilever_run(ccx_io, tmp_path_factory):
    if ccx_io.ccx_executable() is None:
        pytest.skip("ccx (calculix-ccx) is not installed: the CalculiX files cannot be made")
    folder = tmp_path_factory.mktemp("ccx")
    deck = folder / "beam.inp"
    deck.write_text(_cantilever())
    return ccx_io.run_ccx(ccx_io.frequency_input(deck, 6), folder / "run", "beam")


def test_frequencies_of_the_dat_are_those_of_the_exported_matrices(ccx_io, cantilever_run):
    table = ccx_io.read_frequencies(cantilever_run.with_suffix(".dat"))
    mats = ccx_io.read_matrices(cantilever_run)
    assert mats.K.shape == (3 * 16, 3 * 16)  # 20 nodes, the 4 clamped ones removed
    assert 1 not in set(mats.node) and (mats.K - mats.K.T).count_nonzero() == 0
    lam = sla.eigh(mats.K.toarray(), mats.M.toarray(), eigvals_only=True)[:6]
    np.testing.assert_allclose(table["eigenvalue"], lam, rtol=1e-5)
    assert table["frequency_hz"][0] > 0 and len(table["mode"]) == 6


def test_matrix_rows_name_node_and_direction(ccx_io, cantilever_run):
    mats = ccx_io.read_matrices(cantilever_run)
    rows = mats.rows([20], (1, 2, 3))
    assert list(mats.node[rows]) == [20, 20, 20] and list(mats.direction[rows]) == [1, 2, 3]
    with pytest.raises(KeyError, match="not free"):
        mats.rows([1])


def test_input_keeps_the_model_data_of_the_deck(ccx_io, tmp_path):
    (tmp_path / "mesh.msh").write_text("*NODE\n1, 0, 0, 0\n")
    deck = tmp_path / "deck" / "blade.inp"
    deck.parent.mkdir()
    deck.write_text("*HEADING\n*include, input=../mesh.msh\n*STEP\n*STATIC\n*END STEP\n")
    text = ccx_io.frequency_input(deck, 12)
    assert f"input={(tmp_path / 'mesh.msh').resolve()}" in text
    assert "*STATIC" not in text and "*FREQUENCY\n12\n" in text
    assert "SOLVER=MATRIXSTORAGE" in text and text.count("*END STEP") == 2
