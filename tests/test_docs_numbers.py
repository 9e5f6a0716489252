"""Numbers the README quotes from the benchmarks match the files they come from."""

import json
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text()


def test_femrub_paper_time_is_the_benchmarks():
    costs = json.loads((ROOT / "docs" / "performance" / "siconos.json").read_text())["costs"]
    paper = costs["femrub_paper"]
    quoted = re.search(r"`femrub paper` takes ([\d.]+) s wall \(([\d.]+) s CPU, (\d+) MiB", README)
    assert quoted, "README no longer quotes `femrub paper`'s time in the expected words"
    assert quoted.groups() == (
        f"{paper['wall']:.1f}",
        f"{paper['cpu']:.1f}",
        f"{paper['peak_rss_mib']:.0f}",
    ), "README's `femrub paper` time differs from docs/performance/siconos.json"


def test_first_run_compile_time_is_the_benchmarks():
    page = (ROOT / "docs" / "performance" / "rotor37-costs.md").read_text()
    measured = re.search(r"first compilation ([\d.]+) s", page)
    quoted = re.search(r"compiles them first, which took\s+([\d.]+) s", README)
    assert measured and quoted
    assert quoted.group(1) == measured.group(1), (
        "README's first-run compile time differs from benchmarks/step_cost.py's table"
    )
