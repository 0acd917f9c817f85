"""The keys by which the `paper` preset follows the TTP authors' RT unit and application beyond
their configuration file, measured against the authors' simulator in reports/correlation and
cited in docs/paper-preset.md, as `rtsim --set` assignments that switch them off again.
scripts/paper/experiments.py runs the paper's main figures without them (`without_*` runs) beside
the preset, to show what they weigh. Standard library only."""

WITHOUT_KEYS = [
    # The preset's `true`: a node read joins its warp's read of the same 32 B chunk queued or in
    # flight (abstract_hardware_model.cc l.1051-1062, 1113, 1148-1186 of the fork).
    "rt.merge_in_flight=false",
    # The preset's 5.5: the shader code's reads that reach L2, per ray after each trace, the median
    # over the 7 scenes of the reference's 64x64 DFS runs (reports/correlation, "The shaders' memory
    # traffic").
    "workload.shader_reads=0",
]


def set_arguments():
    """WITHOUT_KEYS as rtsim arguments: ["--set", "k=v", ...]."""
    return [a for k in WITHOUT_KEYS for a in ("--set", k)]
