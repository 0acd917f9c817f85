#!/usr/bin/env python3
"""Writes waveforms/rtunit.gtkw, GTKWave's save file for rtsim's VCD traces, grouped by the blocks
of the hardware: per RT unit its warp scheduler, memory access queue, response FIFO, prefetch
queue and TTP's prefetches per window; the traced warp's threads (stack depth and TTP state);
the L1s, the L2 slices and DRAM. It lists the mobile preset's 8 RT units, 8 L1s and 4 L2 slices
and warp-buffer slot 0 of SM 0 (--trace-warp 0:0); GTKWave skips names a trace lacks, and
tests/waveform_gtkw_test.py checks that a trace has every name listed here.
Usage: waveform_gtkw.py [--check]   (--check: exit 1 if the file differs from what this writes)"""
import pathlib
import sys

OUT = pathlib.Path(__file__).resolve().parent.parent / "waveforms" / "rtunit.gtkw"
SMS, L2_SLICES, WARP_SIZE, TRACED = 8, 4, 32, (0, 0)

ANALOG, SIGNED, REAL, BLANK, OPEN, CLOSE = "@8024", "@420", "@24", "@20000", "@800200", "@1000200"


def analog(name):  # an analog step plot three rows high
    return [ANALOG, f"SystemC.{name}[31:0]", BLANK, "-", "-"]


def group(title, rows):
    return [OPEN, f"-{title}"] + rows + [CLOSE, f"-{title}"]


def text():
    lines = [
        "[*] rtunit waveforms, grouped by the RT unit's blocks (mobile preset: 8 RT units, 8 L1s, 4 L2 slices).",
        "[*] Written by scripts/waveform_gtkw.py; every name is checked against a trace by tests/waveform_gtkw_test.py.",
        "[*] Produce the trace with: build/rtsim --scene cornell --fidelity at --prefetcher ttp --vcd out/wave.vcd --trace-warp 0:0",
        "[*] Open it zoomed to fit: gtkwave --rcvar 'do_initial_zoom_fit 1' out/wave.vcd waveforms/rtunit.gtkw",
        "[*] Flags: @420 signed decimal (stack depths, TTP states, the picked slot: -1 is none), @8024 analog steps",
        "[*] (queues, occupancies, counts), each followed by two @20000 blank rows that make its plot three rows high.",
        '[dumpfile] "out/wave.vcd"',
        "[timestart] 0",
        "[size] 1600 1000",
        "[sst_width] 280",
        "[signals_width] 380",
        "[sst_expanded] 1",
    ]
    for u in range(SMS):
        p = f"rt_unit_{u}"
        rows = analog(f"{p}.warp_buffer_occupancy")
        rows += [SIGNED, f"SystemC.{p}.warp_scheduler.picked_slot[31:0]"] + analog(f"{p}.warp_scheduler.ready_warps")
        rows += analog(f"{p}.memory_access_queue_depth") + analog(f"{p}.response_fifo_depth") + analog(f"{p}.active_threads")
        rows += analog(f"{p}.prefetch_queue_depth")
        for k in ("sent", "dropped", "late"):
            rows += analog(f"{p}.ttp.prefetches_{k}_window")
        lines += group(f"RT unit {u}", rows)
        if u == TRACED[0]:
            sm, slot = TRACED
            rows = []
            for t in range(WARP_SIZE):
                base = f"SystemC.rt_unit_{sm}.warp{slot}.thread{t}"
                rows += [SIGNED, f"{base}.stack_depth[31:0]", SIGNED, f"{base}.ttp_state[31:0]"]
            lines += group(f"Traced warp (SM {sm}, slot {slot}): stack depth and TTP state per thread", rows)
    for i in range(SMS):
        lines += group(f"L1 {i}", analog(f"l1_{i}.mshr_occupancy") + [REAL, f"SystemC.l1_{i}.miss_rate_window"])
    for i in range(L2_SLICES):
        lines += group(f"L2 slice {i}", analog(f"l2_{i}.mshr_occupancy") + [REAL, f"SystemC.l2_{i}.miss_rate_window"])
    lines += group("DRAM", analog("dram.queue_depth") + [REAL, "SystemC.dram.bandwidth_utilisation_window"])
    return "\n".join(lines) + "\n"


def main():
    new = text()
    if sys.argv[1:] == ["--check"]:
        if OUT.read_text() != new:
            sys.exit(f"{OUT} differs from what scripts/waveform_gtkw.py writes: run it")
        print(f"{OUT}: as written")
        return
    OUT.write_text(new)
    print(f"wrote {OUT}")


if __name__ == "__main__":
    main()
