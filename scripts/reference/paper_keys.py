"""What the TTP authors' RT unit and application do that rtunit's `paper` preset leaves off, as
`rtsim --set` assignments: measured against the authors' simulator in reports/correlation and cited
in docs/paper-preset.md. correlate.py runs the `paper` preset with them (the reference's paper-*
configurations); scripts/paper/experiments.py runs the paper's main figures with them beside the
preset (`authors_*` runs). Standard library only."""

PAPER_KEYS = [
    # A node read joins its warp's read of the same 32 B chunk queued or in flight
    # (abstract_hardware_model.cc l.1051-1062, 1113, 1148-1186 of the fork).
    "rt.merge_in_flight=true",
    # The shader code's reads that reach L2, per ray after each trace: the median over the 7 scenes
    # of the reference's 64x64 DFS runs (reports/correlation, "The shaders' memory traffic").
    "workload.shader_reads=5.5",
]


def set_arguments():
    """PAPER_KEYS as rtsim arguments: ["--set", "k=v", ...]."""
    return [a for k in PAPER_KEYS for a in ("--set", k)]
