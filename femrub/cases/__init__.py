"""Reference cases: the paper's bar and its reproduction, analytic solutions."""
