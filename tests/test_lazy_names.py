"""A package's lazy name stays the object it names after its submodule of the same name is
imported (``import femrub.geometry.naca_blade`` binds the module on the package)."""

import subprocess
import sys


def test_a_submodule_import_does_not_hide_the_function_of_its_name():
    code = (
        "import femrub.geometry.naca_blade, femrub.geometry.box_blade\n"
        "import femrub.geometry as g\n"
        "assert callable(g.naca_blade) and callable(g.box_blade), (g.naca_blade, g.box_blade)\n"
        "from femrub.geometry import naca_blade\n"
        "assert callable(naca_blade)\n"
        "from femrub.geometry.naca_blade import naca_sections\n"
        "assert callable(naca_sections)\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
