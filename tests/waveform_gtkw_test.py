#!/usr/bin/env python3
"""Every signal waveforms/rtunit.gtkw names is in a trace rtsim writes (AT, TTP, the save file's
own frame and traced warp), and the save file is what scripts/waveform_gtkw.py writes.
Usage: waveform_gtkw_test.py RTSIM SOURCE_DIR"""
import os
import re
import subprocess
import sys
import tempfile

rtsim, src = sys.argv[1], sys.argv[2]
gtkw = open(os.path.join(src, "waveforms", "rtunit.gtkw")).read()
subprocess.run([sys.executable, os.path.join(src, "scripts", "waveform_gtkw.py"), "--check"], check=True)
with tempfile.TemporaryDirectory() as tmp:
    subprocess.run([rtsim, "--scene", "cornell", "--fidelity", "at", "--prefetcher", "ttp", "--width", "16", "--height", "16",
                    "--vcd", f"{tmp}/w.vcd", "--trace-warp", "0:0", "-q"], check=True)
    traced, scope = set(), []
    with open(f"{tmp}/w.vcd") as f:
        for line in f:
            if line.startswith("$enddefinitions"):
                break
            w = line.split()
            if w[:2] == ["$scope", "module"]:
                scope.append(w[2])
            elif w[:1] == ["$upscope"]:
                scope.pop()
            elif w[:1] == ["$var"]:
                # $var wire 32 id name [31:0] $end  /  $var real 1 id name $end
                name = ".".join(scope + [w[4]]) + (w[5] if w[5].startswith("[") else "")
                traced.add(name)
named = [l for l in gtkw.splitlines() if l.startswith("SystemC.")]
missing = [n for n in named if n not in traced]
for n in missing[:20]:
    print(f"not in the trace: {n}")
print(f"{len(named)} signals named, {len(named) - len(missing)} in the trace")
sys.exit(1 if missing or not named else 0)
