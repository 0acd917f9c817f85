#!/usr/bin/env python3
"""Run the reference simulator (Vulkan-sim TTP fork + Mesa lavapipe fork + LumiBench's
RayTracingInVulkan) over a matrix of scenes, frame sizes and configurations, and collect the
statistics it prints into one CSV file.

The script only RUNS an installation that was built elsewhere; it never builds or patches one.
The installation root (--vsim ROOT) must be laid out like this:

    ROOT/env-vsim.sh                          environment (sourced in a subshell before each run)
    ROOT/vulkan-sim/configs/updated-config/   MOBILE-gpgpusim.config, config_turing_islip.icnt
    ROOT/vulkan-sim/configs/tested-cfgs/MOBILE/  gpgpusim.config, config_turing_islip.icnt
    ROOT/mesa-vulkan-sim/src/                 Mesa sources (lavapipe runs a script from there)
    ROOT/RayTracingInVulkan/build/linux/bin/RayTracer
    ROOT/RayTracingInVulkan/build/linux/assets/
    ROOT/VERSIONS                             optional: lines "vulkan_sim=<commit>", "mesa=...", "rtiv=..."

Matrix items are SCENE:WxH:SPP:CONFIG, for example ship:32x32:1:ttp.
  SCENE   wknd ship bunny ref bath sprng party (LumiBench --scene 1 20 18 30 31 11 12)
  CONFIG  dfs      -BFS_based_traversal 0 -stack_trend_prefetch 0
          dfs-ttp  -BFS_based_traversal 0 -stack_trend_prefetch 1
          base     -BFS_based_traversal 1 -stack_trend_prefetch 0
          ttp      -BFS_based_traversal 1 -stack_trend_prefetch 1   (the fork's config as shipped)
  These four are the fork's configs/updated-config/MOBILE-gpgpusim.config (64 KB L1, 16 RT warps,
  intersection latencies 2,4,4,2,4,4,4, BookSim interconnect) with the two switches set.
  dfs-perfect-up, dfs-perfect-down (and paper-dfs-perfect-up, paper-dfs-perfect-down): DFS
          without TTP, with the paper's limit studies (section 6: 2nd and later pops after a push,
          or 1st pops, answered as L1 hits). The fork has no limit study: these need the
          installation built with limit-study.patch (in this folder), and the run fails
          ("no-limit-study") where the simulator does not print that it applied one.
  paper-dfs-park: DFS without TTP, with Park et al.'s prefetcher as the paper's section 6
          describes it (prefetches from the stack during each primitive leaf's test, as many 32 B
          chunks as the config's QUAD intersection latency has cycles, next pop first). The fork
          has no Park code: this needs the installation built with park.patch (in this folder),
          and fails the same way ("no-limit-study") where the simulator does not print that it
          applied it.
  paper-dfs, paper-dfs-ttp, paper-base, paper-ttp: the same switches on
  configs/tested-cfgs/MOBILE/gpgpusim.config (32 KB L1, 4 RT warps, latencies 4,8,8,4,8,8,8, the
  built-in crossbar: the paper's Table 2, and rtunit's `paper` preset), where the two switches
  are appended (that file does not set them).

Each run gets a private directory OUTDIR/runs/<tag>/ laid out like the application's repository,
so that LumiBench's SceneList.cpp finds its files where it looks for them (paths relative to the
working directory, which is build/linux/bin):

    <run>/rtiv/build/linux/bin/      cwd: RayTracer (symlink), gpgpusim.config, config_turing_islip.icnt
    <run>/rtiv/build/linux/assets/   "../assets": the build's assets mirrored by symlinks; models/ holds
                                     the scene's stand-in models (written by this script)
    <run>/rtiv/Scenes/<Folder>/      "../../../Scenes/<Folder>": symlinks to the shared scene's files
    <run>/mroot/                     private MESA_ROOT (gpgpusimShaders/ + src -> ROOT/mesa-vulkan-sim/src)

so several runs can go at once (--jobs). Results:

    OUTDIR/reference.csv             one row per attempt (appended; items already there with exit
                                     code 0 and status "ok" are skipped, so an interrupted matrix
                                     resumes). status: ok | crashed-at-exit (statistics complete,
                                     then the process died) | no-stats | failed | timeout |
                                     no-limit-study (a limit-study or Park CONFIG on an
                                     installation without its patch). Items
                                     that are not ok are tried again (--retries); use the ok rows.
    OUTDIR/logs/<tag>.log.gz         the run's full stdout + stderr
    OUTDIR/images/<tag>.ppm          the frame the simulator wrote
    OUTDIR/models/                   the generated stand-in models (bunny.obj, lucy.obj)

Standard library only (Python >= 3.9).
"""

import argparse
import concurrent.futures
import csv
import datetime
import fcntl
import gzip
import hashlib
import math
import os
import re
import shutil
import signal
import subprocess
import sys
import threading
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "sweep"))
from manifest import sha256 as sha256_file  # noqa: E402  (the sweeps' file hash)

# ----------------------------------------------------------------------------------------------
# Scenes and configurations
# ----------------------------------------------------------------------------------------------

# LumiBench scene ids are the 0-based index into SceneList::AllScenes (RayTracingInVulkan
# src/SceneList.cpp). For each scene: which files the application reads, and from where in the
# shared scene folder (--scenes) they come.
#   models: files placed into assets/models/ (read as "../assets/models/<name>"):
#           ("link", subdir, file)  symlink to SHARED/subdir/file (exact asset)
#           ("gen", generator)      written by this script (a stand-in for a missing asset)
#   folder: (Scenes folder name, shared subdir): every file of the shared subdir is linked into
#           Scenes/<name>/ (read as "../../../Scenes/<name>").
SCENES = {
    "wknd": {"id": 1},                                           # procedural spheres only
    "ship": {"id": 20, "models": {
        "karimSchooner.obj": ("link", "ship", "karimSchooner.obj"),
        "karimSchooner.mtl": ("link", "ship", "karimSchooner.mtl")}},
    "bunny": {"id": 18, "models": {"bunny.obj": ("gen", "bunny")}},
    "ref": {"id": 30, "models": {"lucy.obj": ("gen", "lucy")}},
    "bath": {"id": 31, "folder": ("Bathroom", "bath")},
    "sprng": {"id": 11, "folder": ("Blender_2.80", "sprng")},
    "party": {"id": 12, "folder": ("Blender_2.83", "party")},
}

# Configuration files of the fork: (gpgpusim.config, interconnect file).
CONFIG_SETS = {
    "updated": ("vulkan-sim/configs/updated-config/MOBILE-gpgpusim.config",
                "vulkan-sim/configs/updated-config/config_turing_islip.icnt"),
    "tested": ("vulkan-sim/configs/tested-cfgs/MOBILE/gpgpusim.config",
               "vulkan-sim/configs/tested-cfgs/MOBILE/config_turing_islip.icnt"),
}
# CONFIG -> (configuration set, BFS_based_traversal, stack_trend_prefetch)
CONFIGS = {"dfs": ("updated", 0, 0), "dfs-ttp": ("updated", 0, 1), "base": ("updated", 1, 0), "ttp": ("updated", 1, 1),
           "paper-dfs": ("tested", 0, 0), "paper-dfs-ttp": ("tested", 0, 1), "paper-base": ("tested", 1, 0),
           "paper-ttp": ("tested", 1, 1),
           "dfs-perfect-up": ("updated", 0, 0), "dfs-perfect-down": ("updated", 0, 0),
           "paper-dfs-perfect-up": ("tested", 0, 0), "paper-dfs-perfect-down": ("tested", 0, 0),
           "paper-dfs-park": ("tested", 0, 0)}
# Our instrumentation patches (this folder), chosen by a CONFIG's suffix: suffix -> (the mode kept
# in the CSV's limit_study column, the environment variable that turns the patch on, the patch).
INSTRUMENTS = {"-perfect-up": ("perfect-up", "RTSIM_LIMIT_STUDY", "limit-study.patch"),
               "-perfect-down": ("perfect-down", "RTSIM_LIMIT_STUDY", "limit-study.patch"),
               "-park": ("park", "RTSIM_PARK", "park.patch")}


def instrument(config):
    """The instrumentation a CONFIG asks for: (mode, environment variable, patch), or ('', '', '')."""
    for suffix, inst in INSTRUMENTS.items():
        if config.endswith(suffix):
            return inst
    return ("", "", "")


def quad_latency(config_text, config_file):
    """The QUAD leaf's test latency of a fork configuration file: the 5th of
    -gpgpu_rt_intersection_latency (STRUCTURE, INTERNAL, INSTANCE, DESCRIPTOR, QUAD, QUAD_HIT,
    PROCEDURAL; shader.h l.1621-1628)."""
    m = re.findall(r"(?m)^-gpgpu_rt_intersection_latency[ \t]+(\S+)", config_text)
    if len(m) != 1 or len(m[0].split(",")) != 7:
        raise RuntimeError(f"{config_file}: expected one -gpgpu_rt_intersection_latency with 7 values, found {m}")
    return int(m[0].split(",")[4])


RTIV_BUILD = "RayTracingInVulkan/build/linux"

# ----------------------------------------------------------------------------------------------
# Stand-in models
# ----------------------------------------------------------------------------------------------
# Our simulator places an object mesh as  world = T(t) * R_y(75 deg) * S(s) * normalise(v),  where
# normalise moves the bounding box's bottom centre (x, z at the box centre, y at the box minimum)
# to the origin and scales the height (y extent) to 1. LumiBench bakes
#     vertex = T_L * S_L * R_L * v      (glm: rotate(scale(translate(I, t_L), s_L), 75 deg, Y))
# into the loaded OBJ. A stand-in file v' = inverse(T_L * S_L * R_L) * world therefore lands where
# our simulator puts the object.
#   bunny: LumiBench t_L = (173, 5, -307), s_L = 200; ours is the same placement, so v' = normalise(v).
#   lucy (REF, the Stanford dragon as stand-in): LumiBench t_L = (173, -9, -377), s_L = 0.6;
#          ours t = (230, 0, -330), s = 200.

ROT_Y_DEG = 75.0


def rot_y(deg):
    """3x3 rotation about +Y (right-handed, as glm::rotate)."""
    a = math.radians(deg)
    c, s = math.cos(a), math.sin(a)
    return ((c, 0.0, s), (0.0, 1.0, 0.0), (-s, 0.0, c))


def mat_vec(m, v):
    return tuple(m[i][0] * v[0] + m[i][1] * v[1] + m[i][2] * v[2] for i in range(3))


def transpose(m):
    return tuple(tuple(m[j][i] for j in range(3)) for i in range(3))


def bottom_centre_normaliser(vertices, faces):
    """(centre, scale) such that normalise(v) = scale * (v - centre); bounds over the vertices
    the faces use (as our simulator computes a mesh's bounds over its primitives)."""
    used = set()
    for f in faces:
        used.update(f)
    pts = [vertices[i] for i in sorted(used)] if used else vertices
    lo = [min(p[k] for p in pts) for k in range(3)]
    hi = [max(p[k] for p in pts) for k in range(3)]
    h = hi[1] - lo[1]
    scale = 1.0 / h if h > 0 else 1.0
    centre = (0.5 * (lo[0] + hi[0]), lo[1], 0.5 * (lo[2] + hi[2]))
    return centre, scale


def read_obj_vf(path):
    """Vertices (float64 xyz) and faces (0-based vertex indices) of a plain OBJ file."""
    vertices, faces = [], []
    with open(path, "r", encoding="utf-8", errors="replace") as f:
        for line in f:
            if line.startswith("v "):
                x, y, z = line.split()[1:4]
                vertices.append((float(x), float(y), float(z)))
            elif line.startswith("f "):
                idx = []
                for tok in line.split()[1:]:
                    i = int(tok.split("/")[0])
                    idx.append(i - 1 if i > 0 else len(vertices) + i)
                faces.append(tuple(idx))
    return vertices, faces


def read_ply_vf(path):
    """Vertices and faces of an ASCII PLY file (optionally gzipped)."""
    opener = gzip.open if path.endswith(".gz") else open
    with opener(path, "rt", encoding="ascii", errors="replace") as f:
        if f.readline().strip() != "ply":
            raise ValueError(f"{path}: not a PLY file")
        elements = []  # [name, count, [property names]]
        while True:
            line = f.readline()
            if not line:
                raise ValueError(f"{path}: no end_header")
            tok = line.split()
            if not tok:
                continue
            if tok[0] == "format" and tok[1] != "ascii":
                raise ValueError(f"{path}: only ASCII PLY is supported")
            if tok[0] == "element":
                elements.append([tok[1], int(tok[2]), []])
            elif tok[0] == "property":
                elements[-1][2].append(tok[-1])
            elif tok[0] == "end_header":
                break
        vertices, faces = [], []
        for name, count, props in elements:
            if name == "vertex":
                ix, iy, iz = props.index("x"), props.index("y"), props.index("z")
                for _ in range(count):
                    t = f.readline().split()
                    vertices.append((float(t[ix]), float(t[iy]), float(t[iz])))
            elif name == "face":
                for _ in range(count):
                    t = f.readline().split()
                    n = int(t[0])
                    faces.append(tuple(int(x) for x in t[1:1 + n]))
            else:
                for _ in range(count):
                    f.readline()
    return vertices, faces


def write_obj(path, header, vertices, faces):
    """Write vertices (9 significant digits) and 1-based faces; atomically (tmp + rename)."""
    tmp = f"{path}.tmp{os.getpid()}"
    with open(tmp, "w", encoding="ascii", newline="\n") as f:
        for line in header:
            f.write(f"# {line}\n")
        for x, y, z in vertices:
            f.write(f"v {x:.9g} {y:.9g} {z:.9g}\n")
        for face in faces:
            f.write("f " + " ".join(str(i + 1) for i in face) + "\n")
    os.replace(tmp, path)


def place_for_lumibench(vertices, faces, ours_t, ours_s, lumi_t, lumi_s):
    """v' = inverse(T_L * S_L * R_L) * (T * R * S * normalise(v)), in float64."""
    centre, nscale = bottom_centre_normaliser(vertices, faces)
    r = rot_y(ROT_Y_DEG)
    r_inv = transpose(r)
    out = []
    for v in vertices:
        n = tuple(nscale * (v[k] - centre[k]) for k in range(3))
        w = mat_vec(r, tuple(ours_s * c for c in n))
        w = tuple(w[k] + ours_t[k] for k in range(3))
        p = mat_vec(r_inv, tuple(w[k] - lumi_t[k] for k in range(3)))
        out.append(tuple(c / lumi_s for c in p))
    return out


def gen_bunny(shared, out_path):
    src = os.path.join(shared, "bunny", "stanford-bunny.obj")
    vertices, faces = read_obj_vf(src)
    centre, s = bottom_centre_normaliser(vertices, faces)
    norm = [tuple(s * (v[k] - centre[k]) for k in range(3)) for v in vertices]
    write_obj(out_path, [
        "Stanford bunny (stanford-bunny.obj) normalised: bounding-box bottom centre at the origin,",
        "height 1. LumiBench BUNNY then applies T(173,5,-307) * S(200) * R_y(75 deg).",
        f"source sha256 {sha256_file(src)}"], norm, faces)
    return src


def gen_lucy(shared, out_path):
    src = os.path.join(shared, "dragon", "dragon_vrip_res2.ply.gz")
    vertices, faces = read_ply_vf(src)
    placed = place_for_lumibench(vertices, faces, ours_t=(230.0, 0.0, -330.0), ours_s=200.0,
                                 lumi_t=(173.0, -9.0, -377.0), lumi_s=0.6)
    write_obj(out_path, [
        "Stanford dragon (dragon_vrip_res2.ply.gz) as a stand-in for LumiBench's lucy.obj (REF).",
        "After LumiBench's T(173,-9,-377) * S(0.6) * R_y(75 deg) it lies at",
        "T(230,0,-330) * R_y(75 deg) * S(200) * normalise(v) (bottom centre at origin, height 1).",
        f"source sha256 {sha256_file(src)}"], placed, faces)
    return src


GENERATORS = {"bunny": gen_bunny, "lucy": gen_lucy}

# ----------------------------------------------------------------------------------------------
# Statistics printed by the simulator at kernel exit
# ----------------------------------------------------------------------------------------------
# Plain "name = value" lines of the final statistics block (top level, outside the RT blocks).
TOP_STATS = [
    "gpu_sim_cycle", "gpu_sim_insn", "gpu_ipc", "gpu_tot_sim_cycle", "gpu_tot_sim_insn",
    "gpu_tot_issued_cta", "gpu_occupancy", "gpu_stall_dramfull", "gpu_stall_icnt2sh",
    "partiton_level_parallism", "partiton_level_parallism_util", "L2_BW",
    # ray tracing
    "rt_n_total_rays", "rt_n_closesthit_rays", "rt_n_anyhit_rays", "rt_num_hits", "rt_num_any_hits",
    "rt_avg_nodes_per_ray", "rt_max_nodes_per_ray", "rt_tot_nodes_per_ray", "rt_max_tree_depth",
    "rt_avg_warp_latency", "rt_avg_thread_latency", "rt_avg_efficiency", "rt_avg_warp_occupancy",
    "rt_avg_op_intensity", "rt_avg_performance", "rt_writes", "rt_limit_study_hits", "rt_park_prefetch_records",
    "rt_max_mem_store_q",
    "rt_avg_mem_store_cycles", "rt_total_cycles", "rt_total_cycles_sum",
    "gpgpu_n_rt_insn", "gpgpu_n_rt_access_insn",
    # L1D (the RT unit uses L1 as its RT cache: -gpgpu_rt_use_l1 1)
    "L1D_total_cache_accesses", "L1D_total_cache_misses", "L1D_total_cache_miss_rate",
    "L1D_total_cache_pending_hits", "L1D_total_cache_reservation_fails",
    "L1D_cache_data_port_util", "L1D_cache_fill_port_util",
    # L2
    "L2_total_cache_accesses", "L2_total_cache_misses", "L2_total_cache_miss_rate",
    "L2_total_cache_pending_hits", "L2_total_cache_reservation_fails",
    "L2_cache_data_port_util", "L2_cache_fill_port_util",
    # global memory traffic
    "gpgpu_n_mem_read_global", "gpgpu_n_mem_write_global", "gpgpu_n_global_load_insn",
    "gpgpu_n_global_store_insn", "gpgpu_n_stall_shd_mem",
    "icnt_total_pkts_mem_to_simt", "icnt_total_pkts_simt_to_mem",
    # memory latencies (cycles)
    "maxmflatency", "averagemflatency", "max_icnt2mem_latency", "avg_icnt2mem_latency",
    "maxmrqlatency", "avg_mrq_latency", "max_icnt2sh_latency", "avg_icnt2sh_latency",
    # DRAM totals
    "total dram reads", "total dram writes",
]
# Breakdown entries of the core (L1) and L2 caches for global reads.
ACC_OUTCOMES = ["HIT", "HIT_RESERVED", "MISS", "SECTOR_MISS", "RESERVATION_FAIL", "PREFETCH_HIT"]
BREAKDOWN_STATS = (
    [(f"Total_core_cache_stats_breakdown[GLOBAL_ACC_R][{o}]", f"L1D_global_r_{o.lower()}")
     for o in ACC_OUTCOMES] +
    [(f"L2_cache_stats_breakdown[GLOBAL_ACC_R][{o}]", f"L2_global_r_{o.lower()}")
     for o in ACC_OUTCOMES])
# Entries of the two RT blocks: RT_Total_core_cache_stats_breakdown (RT unit accesses to its
# cache, prefix rtc_) and RT_L2_cache_stats_breakdown (RT accesses reaching L2, prefix rtl2_).
# HIT_RESERVED is a hit on a line whose fill is pending (what other simulators call an MSHR hit).
RT_BLOCKS = {"RT_Total_core_cache_stats_breakdown:": "rtc_",
             "RT_L2_cache_stats_breakdown:": "rtl2_"}
RT_BLOCK_STATS = (
    [("rt_read_cold_miss", "read_cold_miss"), ("rt_read_other_miss", "read_other_miss"),
     ("rt_total_misses", "total_misses"), ("m_num_prefetched", "num_prefetched"),
     ("m_num_unused_prefetched", "num_unused_prefetched"), ("accuracy", "prefetch_accuracy"),
     ("coverage", "prefetch_coverage")] +
    [(f"rt_stats[READ][{o}]", f"read_{o.lower()}") for o in ACC_OUTCOMES] +
    [("rt_read_miss_rate", "read_miss_rate"), ("rt_stats[WRITE][MISS]", "write_miss"),
     ("rt_overall_miss_rate", "overall_miss_rate")])
# DRAM: summed (or averaged) over the channels' "DRAM[i]:" blocks.
DRAM_SUMS = ["n_act", "n_pre", "n_req", "n_rd", "n_write", "n_wr_bk", "n_activity"]
DRAM_MEANS = {"bw_util": "dram_bw_util_mean", "dram_eff": "dram_eff_mean",
              "Row_Buffer_Locality": "dram_row_buffer_locality_mean",
              "Row_Buffer_Locality_read": "dram_row_buffer_locality_read_mean",
              "Row_Buffer_Locality_write": "dram_row_buffer_locality_write_mean",
              "Bank_Level_Parallism": "dram_bank_level_parallelism_mean",
              "queue_avg": "dram_queue_avg_mean"}


def stat_columns():
    cols = [re.sub(r"\W+", "_", s).strip("_") for s in TOP_STATS]
    cols += [c for _, c in BREAKDOWN_STATS]
    for prefix in RT_BLOCKS.values():
        cols += [prefix + c for _, c in RT_BLOCK_STATS]
    cols += ["rt_total_cacheline_fetched_sum"]
    cols += ["dram_channels"] + [f"dram_{k}_sum" for k in DRAM_SUMS]
    cols += list(DRAM_MEANS.values())
    cols += ["dram_row_buffer_locality", "dram_avg_row_accesses_per_activate",
             "sim_time_s", "sim_rate_inst_per_s", "sim_rate_cycle_per_s", "n_kernels"]
    return cols


NUM_RE = r"[-+]?(?:\d+\.?\d*(?:[eE][-+]?\d+)?|nan|-nan|inf)"


def parse_stats(log_text):
    """Statistics of the last kernel-exit block of a run log (dict column -> text)."""
    out = {}
    out["n_kernels"] = str(len(re.findall(r"^kernel_name = ", log_text, re.M)))
    start = log_text.rfind("\nkernel_name = ")
    if start < 0:
        return out
    lines = log_text[start + 1:].splitlines()
    top, rt = {}, {}
    block = None
    dram = {k: [] for k in DRAM_SUMS + list(DRAM_MEANS)}
    for line in lines:
        if line in RT_BLOCKS:
            block = RT_BLOCKS[line]
            continue
        if block and not line.startswith("\t"):
            block = None
        m = re.match(r"^\s*(.+?)\s*=\s*(" + NUM_RE + r")", line)
        if block and m:
            rt.setdefault(block + m.group(1), m.group(2))
            continue
        if m:
            top.setdefault(m.group(1), m.group(2))
        # per-channel DRAM lines: "n_cmd=... n_act=926 ... bw_util=0.1148", "n_activity=... dram_eff=..."
        if line.startswith("n_cmd=") or line.startswith("n_activity="):
            for k, v in re.findall(r"(\w+)=(" + NUM_RE + ")", line):
                if k in dram:
                    dram[k].append(float(v))
        mm = re.match(r"^(Row_Buffer_Locality(?:_read|_write)?|Bank_Level_Parallism|queue_avg)"
                      r"\s*=\s*(" + NUM_RE + ")", line)
        if mm:
            dram[mm.group(1)].append(float(mm.group(2)))
        mm = re.match(r"^rt_total_cacheline_fetched\s*=\s*(.*)$", line)
        if mm:
            out["rt_total_cacheline_fetched_sum"] = str(sum(int(x) for x in mm.group(1).split()))
        mm = re.match(r"^average row locality = (\d+)/(\d+) = (" + NUM_RE + ")", line)
        if mm:
            out["dram_avg_row_accesses_per_activate"] = mm.group(3)
        mm = re.match(r"^gpgpu_simulation_time = .*\((\d+) sec\)", line)
        if mm:
            out["sim_time_s"] = mm.group(1)
        mm = re.match(r"^gpgpu_simulation_rate = (\d+) \((inst|cycle)/sec\)", line)
        if mm:
            out[f"sim_rate_{mm.group(2)}_per_s"] = mm.group(1)
    for name in TOP_STATS:
        if name in top:
            out[re.sub(r"\W+", "_", name).strip("_")] = top[name]
    for name, col in BREAKDOWN_STATS:
        if name in top:
            out[col] = top[name]
    for prefix in RT_BLOCKS.values():
        for name, col in RT_BLOCK_STATS:
            if prefix + name in rt:
                out[prefix + col] = rt[prefix + name]
    # DRAM channel aggregates (the per-channel "n_ref" / "Bank_Level_Parallism_Col" figures are
    # uninitialised garbage in this simulator version and are not used)
    nch = len(dram["n_act"])
    if nch:
        out["dram_channels"] = str(nch)
        for k in DRAM_SUMS:
            if len(dram[k]) == nch:
                out[f"dram_{k}_sum"] = str(int(sum(dram[k])))
        for k, col in DRAM_MEANS.items():
            if dram[k]:
                out[col] = f"{sum(dram[k]) / len(dram[k]):.6g}"
        req, act = sum(dram["n_req"]), sum(dram["n_act"])
        if req > 0:  # row-buffer hits / requests over all channels
            out["dram_row_buffer_locality"] = f"{(req - act) / req:.6g}"
    if "gpu_occupancy" in out:
        out["gpu_occupancy"] = out["gpu_occupancy"].rstrip("%")
    return out


# ----------------------------------------------------------------------------------------------
# Helpers
# ----------------------------------------------------------------------------------------------

def sha256_listing(files):
    """Short fingerprint of a set of files: sha256 over sorted "name sha256" lines."""
    h = hashlib.sha256()
    for name, path in sorted(files):
        h.update(f"{name} {sha256_file(path)}\n".encode())
    return h.hexdigest()[:16]


def utc_now():
    return datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")


def log(msg):
    print(f"[{datetime.datetime.now().strftime('%H:%M:%S')}] {msg}", flush=True)


class Item:
    """One matrix item: SCENE:WxH:SPP:CONFIG."""

    def __init__(self, text):
        m = re.fullmatch(r"\s*([a-z]+):(\d+)x(\d+):(\d+):([a-z-]+)\s*", text)
        if not m:
            raise ValueError(f"bad matrix item {text!r} (expected SCENE:WxH:SPP:CONFIG)")
        self.scene, w, h, spp, self.config = m.groups()
        self.width, self.height, self.spp = int(w), int(h), int(spp)
        if self.scene not in SCENES:
            raise ValueError(f"unknown scene {self.scene!r} (known: {', '.join(SCENES)})")
        if self.config not in CONFIGS:
            raise ValueError(f"unknown config {self.config!r} (known: {', '.join(CONFIGS)})")
        if min(self.width, self.height, self.spp) < 1:
            raise ValueError(f"bad size or spp in {text!r}")

    @property
    def text(self):
        return f"{self.scene}:{self.width}x{self.height}:{self.spp}:{self.config}"

    @property
    def tag(self):
        return f"{self.scene}-{self.width}x{self.height}-{self.spp}spp-{self.config}"

    def key(self):
        return (self.scene, str(self.width), str(self.height), str(self.spp), self.config)


ID_COLUMNS = ["scene", "lumibench_id", "width", "height", "spp", "config", "bfs", "ttp", "limit_study",
              "status", "exit_code", "wall_s", "peak_rss_mb", "started_utc", "finished_utc",
              "vulkan_sim", "mesa", "rtiv", "assets_sha", "scene_dir_order_sha",
              "app_models_loaded", "log", "error"]
CSV_COLUMNS = ID_COLUMNS + stat_columns()


def read_versions(root, fallback):
    """Tool commits from ROOT/VERSIONS ("key=value" or "key value" lines), else --versions."""
    versions = {"vulkan_sim": "", "mesa": "", "rtiv": ""}
    text = ""
    path = os.path.join(root, "VERSIONS")
    if os.path.isfile(path):
        with open(path, encoding="utf-8") as f:
            text = f.read()
    elif fallback:
        text = fallback.replace(",", "\n")
    for line in text.splitlines():
        line = line.split("#", 1)[0].strip()
        m = re.match(r"([\w-]+)\s*[=:\s]\s*(\S+)$", line)
        if m:
            k = m.group(1).lower().replace("-", "_")
            k = {"vulkan_sim": "vulkan_sim", "vulkansim": "vulkan_sim", "mesa_vulkan_sim": "mesa",
                 "raytracinginvulkan": "rtiv", "lumibench": "rtiv"}.get(k, k)
            if k in versions:
                versions[k] = m.group(2)
    return versions


class Csv:
    """reference.csv, appended under an exclusive lock (safe across threads and processes)."""

    def __init__(self, path):
        self.path = path
        self.lock = threading.Lock()

    def _rows(self):
        if not os.path.exists(self.path):
            return [], None
        with open(self.path, newline="", encoding="utf-8") as f:
            r = csv.DictReader(f)
            return list(r), r.fieldnames

    def done(self):
        """Keys of the runs that completed (exit code 0, status ok)."""
        rows, _ = self._rows()
        return {(r["scene"], r["width"], r["height"], r["spp"], r["config"])
                for r in rows if r.get("exit_code") == "0" and r.get("status") == "ok"}

    def append(self, row):
        with self.lock, open(self.path + ".lock", "w") as lk:
            fcntl.flock(lk, fcntl.LOCK_EX)
            rows, header = self._rows()
            new = header is None
            if header and header != CSV_COLUMNS and set(header) < set(CSV_COLUMNS):
                # columns added since the file was written: rewrite it whole with them (empty in
                # the older rows), to a temporary name first
                with open(self.path + ".tmp", "w", newline="", encoding="utf-8") as f:
                    w = csv.DictWriter(f, fieldnames=CSV_COLUMNS)
                    w.writeheader()
                    w.writerows(rows)
                os.replace(self.path + ".tmp", self.path)
                header = CSV_COLUMNS
            if header and header != CSV_COLUMNS:
                log(f"warning: {self.path} has another column set; writing its columns only")
            with open(self.path, "a", newline="", encoding="utf-8") as f:
                w = csv.DictWriter(f, fieldnames=header or CSV_COLUMNS, extrasaction="ignore")
                if new:
                    w.writeheader()
                w.writerow(row)
                f.flush()
                os.fsync(f.fileno())


# ----------------------------------------------------------------------------------------------
# One run
# ----------------------------------------------------------------------------------------------

class Runner:
    def __init__(self, args, versions, csvfile):
        self.root = args.vsim
        self.shared = args.scenes
        self.out = args.out
        self.nice = args.nice
        self.timeout = args.timeout
        self.keep = args.keep_runs
        self.retries = max(0, args.retries)
        self.stopping = False
        self.versions = versions
        self.csv = csvfile
        self.procs = {}  # pid -> Popen, for clean-up on interrupt
        self.procs_lock = threading.Lock()
        self.generated = {}  # generator name -> path in OUTDIR/models

    # -- stand-in models, generated once per invocation into OUTDIR/models ----------------------
    def generate_models(self, scenes):
        os.makedirs(os.path.join(self.out, "models"), exist_ok=True)
        for scene in sorted(scenes):
            for name, spec in SCENES[scene].get("models", {}).items():
                if spec[0] == "gen" and spec[1] not in self.generated:
                    path = os.path.join(self.out, "models", name)
                    t0 = time.time()
                    src = GENERATORS[spec[1]](self.shared, path)
                    self.generated[spec[1]] = path
                    log(f"wrote {path} from {src} ({time.time() - t0:.1f} s, "
                        f"sha256 {sha256_file(path)[:16]})")

    # -- private run directory -------------------------------------------------------------------
    def prepare(self, item, run):
        """Lay out the run directory; returns (bin dir, MESA_ROOT, fingerprint files, readdir order)."""
        scene = SCENES[item.scene]
        rtiv = os.path.join(run, "rtiv")
        bindir = os.path.join(rtiv, "build", "linux", "bin")
        assets = os.path.join(rtiv, "build", "linux", "assets")
        mroot = os.path.join(run, "mroot")
        for d in (bindir, assets, mroot):
            os.makedirs(d)
        os.symlink(os.path.join(self.root, "mesa-vulkan-sim", "src"), os.path.join(mroot, "src"))
        os.symlink(os.path.join(self.root, RTIV_BUILD, "bin", "RayTracer"),
                   os.path.join(bindir, "RayTracer"))
        shutil.copyfile(os.path.join(self.root, CONFIG_SETS[CONFIGS[item.config][0]][1]),
                        os.path.join(bindir, "config_turing_islip.icnt"))
        self.write_config(item, os.path.join(bindir, "gpgpusim.config"))

        # assets: mirror the build's assets by symlinks; models/ is a real directory so that the
        # scene's stand-ins can be added to (or replace) the build's files
        build_assets = os.path.join(self.root, RTIV_BUILD, "assets")
        for entry in sorted(os.listdir(build_assets)):
            src = os.path.join(build_assets, entry)
            if entry == "models" and os.path.isdir(src):
                continue
            os.symlink(src, os.path.join(assets, entry))
        models = os.path.join(assets, "models")
        os.makedirs(models)
        build_models = os.path.join(build_assets, "models")
        ours = scene.get("models", {})
        if os.path.isdir(build_models):
            for entry in sorted(os.listdir(build_models)):
                if entry not in ours:
                    os.symlink(os.path.join(build_models, entry), os.path.join(models, entry))
        fingerprint = []
        for name, spec in ours.items():
            dst = os.path.join(models, name)
            if spec[0] == "link":
                src = os.path.join(self.shared, spec[1], spec[2])
                os.symlink(src, dst)
            else:
                shutil.copyfile(self.generated[spec[1]], dst)
            fingerprint.append((name, dst))

        # directory scenes: Scenes/<Folder>/ holds symlinks to every file of the shared folder
        order = []
        if "folder" in scene:
            folder, sub = scene["folder"]
            sdir = os.path.join(rtiv, "Scenes", folder)
            os.makedirs(sdir)
            src_dir = os.path.join(self.shared, sub)
            for entry in sorted(os.listdir(src_dir)):
                src = os.path.join(src_dir, entry)
                if os.path.isfile(src):
                    os.symlink(src, os.path.join(sdir, entry))
                    if entry.endswith((".obj", ".mtl", ".camera")):
                        fingerprint.append((entry, src))
            # the application iterates the folder in readdir order (std::filesystem::
            # directory_iterator); that order fixes the model / BLAS / instance numbering
            order = [e for e in os.listdir(sdir) if e.endswith((".obj", ".camera"))]
            with open(os.path.join(run, "scene_dir_order.txt"), "w") as f:
                f.write("\n".join(order) + "\n")
        return bindir, mroot, fingerprint, order

    def write_config(self, item, dst):
        """The fork's configuration file with the two traversal/prefetch switches set: replaced
        where the file sets them, appended where it does not; each must then appear exactly once,
        with the wanted value."""
        cset, bfs, ttp = CONFIGS[item.config]
        config_file = CONFIG_SETS[cset][0]
        with open(os.path.join(self.root, config_file), encoding="utf-8") as f:
            text = f.read()
        want = {"BFS_based_traversal": bfs, "stack_trend_prefetch": ttp}
        for opt, val in want.items():
            text, n = re.subn(rf"(?m)^-{opt}[ \t]+\S+", f"-{opt} {val}", text)
            if n == 0:
                text = text.rstrip("\n") + f"\n-{opt} {val}\n"
            elif n != 1:
                raise RuntimeError(f"{config_file}: -{opt} appears {n} times (expected at most once)")
        for opt, val in want.items():
            lines = re.findall(rf"(?m)^-{opt}\b.*$", text)
            if lines != [f"-{opt} {val}"]:
                raise RuntimeError(f"config edit failed for -{opt}: {lines}")
        with open(dst, "w", encoding="utf-8") as f:
            f.write(text)

    # -- run ---------------------------------------------------------------------------------------
    def run(self, item):
        if item.key() in self.csv.done():
            log(f"skip {item.text} (already in the CSV)")
            return None
        run = os.path.join(self.out, "runs", item.tag)
        os.makedirs(run, exist_ok=True)
        lockf = open(os.path.join(run, ".lock"), "w")
        try:
            fcntl.flock(lockf, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            log(f"skip {item.text}: another process is running it in {run}")
            return None
        try:
            for attempt in range(1 + self.retries):
                row = self._run_locked(item, run)
                if row["status"] == "ok" or self.stopping:
                    break
                if attempt < self.retries:
                    log(f"retry {item.text} ({row['status']}, exit {row['exit_code']})")
        finally:
            lockf.close()
        if os.listdir(run) == [".lock"]:  # successful and cleaned up: drop the directory
            os.remove(os.path.join(run, ".lock"))
            os.rmdir(run)
        return row

    def _run_locked(self, item, run):
        # fresh private directory (keep the lock file)
        for entry in os.listdir(run):
            if entry != ".lock":
                p = os.path.join(run, entry)
                if os.path.isdir(p) and not os.path.islink(p):
                    shutil.rmtree(p)
                else:
                    os.remove(p)
        _, bfs, ttp = CONFIGS[item.config]
        mode, env_name, patch = instrument(item.config)
        row = {"scene": item.scene, "lumibench_id": SCENES[item.scene]["id"],
               "width": item.width, "height": item.height, "spp": item.spp,
               "config": item.config, "bfs": bfs, "ttp": ttp, "limit_study": mode,
               **self.versions}
        bindir, mroot, fingerprint, order = self.prepare(item, run)
        row["assets_sha"] = sha256_listing(fingerprint) if fingerprint else "procedural"
        row["scene_dir_order_sha"] = (hashlib.sha256("\n".join(order).encode()).hexdigest()[:16]
                                      if order else "")
        app_args = ["--scene", str(SCENES[item.scene]["id"]), "--width", str(item.width),
                    "--height", str(item.height), "--samples", str(item.spp)]
        # the instrumentation's switch: the limit study's mode, or Park's chunks a leaf test (the
        # QUAD latency of the configuration as written for this run: one 32 B chunk a cycle)
        env_value = mode
        if env_name == "RTSIM_PARK":
            config_path = os.path.join(bindir, "gpgpusim.config")
            with open(config_path, encoding="utf-8") as f:
                env_value = str(quad_latency(f.read(), config_path))
        switch = f"{env_name}={env_value}" if env_name else ""
        # env-vsim.sh cds into vulkan-sim/ and sources its setup_environment: run it in a subshell,
        # then set the private MESA_ROOT (lavapipe writes the shaders' PTX to
        # $MESA_ROOT/gpgpusimShaders/) and start the application from bin/.
        script = ('source "$1/env-vsim.sh" >/dev/null 2>&1; export MESA_ROOT="$2/"; '
                  'unset RTSIM_LIMIT_STUDY RTSIM_PARK; if [ -n "$4" ]; then export "$4"; fi; '
                  'cd "$3" || exit 98; shift 4; exec ./RayTracer "$@"')
        cmd = ["nice", "-n", str(self.nice), "bash", "-c", script, "run_reference",
               self.root, mroot, bindir, switch] + app_args
        logpath = os.path.join(run, "run.log")
        row["started_utc"] = utc_now()
        log(f"start {item.text} ({' '.join(app_args)})")
        t0 = time.monotonic()
        with open(logpath, "wb") as logf:
            logf.write(f"# run_reference.py {item.text}: {' '.join(app_args)} "
                       f"(BFS_based_traversal={bfs} stack_trend_prefetch={ttp}"
                       f"{' ' + switch if switch else ''})\n".encode())
            logf.flush()
            p = subprocess.Popen(cmd, stdout=logf, stderr=subprocess.STDOUT,
                                 stdin=subprocess.DEVNULL, start_new_session=True)
            with self.procs_lock:
                self.procs[p.pid] = p
            status, rusage, timed_out = None, None, False
            while status is None:
                pid, st, ru = os.wait4(p.pid, os.WNOHANG)
                if pid:
                    status, rusage = st, ru
                    break
                if self.timeout and time.monotonic() - t0 > self.timeout and not timed_out:
                    timed_out = True
                    os.killpg(p.pid, signal.SIGKILL)  # the process group this script started
                time.sleep(0.5)
            p.returncode = os.waitstatus_to_exitcode(status)
            with self.procs_lock:
                self.procs.pop(p.pid, None)
        wall = time.monotonic() - t0
        row["finished_utc"] = utc_now()
        row["exit_code"] = p.returncode
        row["wall_s"] = f"{wall:.1f}"
        # ru_maxrss (KiB): the largest resident set of the process and its waited-for children
        row["peak_rss_mb"] = f"{rusage.ru_maxrss / 1024:.0f}"

        with open(logpath, "r", encoding="utf-8", errors="replace") as f:
            text = f.read()
        stats = parse_stats(text)
        row.update(stats)
        row["app_models_loaded"] = len(re.findall(r"^- loading '[^']*\.obj'", text, re.M))
        finished = "Max simulated kernels of" in text
        applied = not switch or switch.replace("=", " = ", 1) in text
        if not applied:
            # the installation was built without the patch: the run is a plain DFS run
            row["status"] = "no-limit-study"
        elif p.returncode == 0 and "gpu_sim_cycle" in stats and finished:
            row["status"] = "ok"
        elif timed_out:
            row["status"] = "timeout"
        elif "gpu_sim_cycle" in stats and finished:
            # the simulation finished and printed its statistics, but the process then died
            # (seen once: a Mesa assertion in util_resource_copy_region while exiting)
            row["status"] = "crashed-at-exit"
        elif p.returncode == 0:
            row["status"] = "no-stats"
        else:
            row["status"] = "failed"
        if row["status"] == "no-limit-study":
            row["error"] = f"the simulator did not apply {env_name}: build it with scripts/reference/{patch}"
        elif row["status"] != "ok":
            row["error"] = first_error(text)
            if p.returncode < 0:
                row["error"] = f"signal {-p.returncode}: {row['error']}"

        # keep the log (gzip) and the frame; drop the bulky per-run files
        logs = os.path.join(self.out, "logs")
        os.makedirs(logs, exist_ok=True)
        gz = os.path.join(logs, f"{item.tag}.log.gz")
        if os.path.exists(gz):  # an earlier attempt: keep it under its time stamp
            stamp = time.strftime("%Y%m%dT%H%M%S", time.gmtime(os.path.getmtime(gz)))
            os.replace(gz, os.path.join(logs, f"{item.tag}.{stamp}.log.gz"))
        with open(logpath, "rb") as src, gzip.open(gz, "wb", compresslevel=6) as dst:
            shutil.copyfileobj(src, dst)
        row["log"] = os.path.relpath(gz, self.out)
        if order:
            with open(os.path.join(logs, f"{item.tag}.scene_dir_order.txt"), "w") as f:
                f.write("\n".join(order) + "\n")
        ppms = sorted(f for f in os.listdir(bindir) if f.endswith(".ppm"))
        if ppms:
            os.makedirs(os.path.join(self.out, "images"), exist_ok=True)
            shutil.copyfile(os.path.join(bindir, ppms[-1]),
                            os.path.join(self.out, "images", f"{item.tag}.ppm"))
        self.csv.append(row)
        if row["status"] == "ok" and not self.keep:
            for entry in os.listdir(run):
                if entry != ".lock":
                    p_ = os.path.join(run, entry)
                    shutil.rmtree(p_) if os.path.isdir(p_) and not os.path.islink(p_) else os.remove(p_)
        else:  # keep the directory for inspection, minus the large instruction trace
            for bulky in ("inst_debug.txt",):
                if os.path.exists(os.path.join(bindir, bulky)):
                    os.remove(os.path.join(bindir, bulky))
        log(f"end   {item.text}: {row['status']} exit {row['exit_code']} "
            f"cycles {row.get('gpu_sim_cycle', '-')} rays {row.get('rt_n_total_rays', '-')} "
            f"wall {row['wall_s']} s rss {row['peak_rss_mb']} MB")
        return row

    def kill_all(self):
        with self.procs_lock:
            for pid in list(self.procs):
                try:
                    os.killpg(pid, signal.SIGTERM)  # only the process groups started here
                except ProcessLookupError:
                    pass


def first_error(text):
    """The first line of a log that looks like the reason of a failure (for the CSV)."""
    pats = [r"terminate called.*", r".*[Ee]xception.*", r".*cannot open.*", r".*No such file.*",
            r".*ERROR.*", r".*[Ss]egmentation fault.*", r".*Assertion.*", r".*[Aa]borted.*"]
    for pat in pats:
        m = re.search(r"^(" + pat + r")$", text, re.M)
        if m:
            return m.group(1).strip()[:300]
    tail = [l for l in text.splitlines() if l.strip()][-1:]
    return tail[0].strip()[:300] if tail else ""


# ----------------------------------------------------------------------------------------------
# Command line
# ----------------------------------------------------------------------------------------------

def check_root(root):
    need = ["env-vsim.sh", *CONFIG_SETS["updated"], *CONFIG_SETS["tested"], os.path.join(RTIV_BUILD, "bin", "RayTracer"),
            os.path.join(RTIV_BUILD, "assets"), os.path.join("mesa-vulkan-sim", "src")]
    missing = [n for n in need if not os.path.exists(os.path.join(root, n))]
    if missing:
        sys.exit(f"{root} is not a reference build root; missing: {', '.join(missing)}")


def main(argv=None):
    ap = argparse.ArgumentParser(
        description=__doc__.split("\n\n", 1)[0],
        epilog=__doc__.split("\n\n", 1)[1],
        formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--vsim", required=True, metavar="ROOT", help="the reference build root")
    ap.add_argument("--scenes", required=True, metavar="SHARED_SCENES_DIR",
                    help="the shared scene folder (ship/, bunny/, dragon/, bath/, sprng/, party/)")
    ap.add_argument("--out", required=True, metavar="OUTDIR", help="output directory")
    ap.add_argument("--matrix", metavar="FILE", action="append", default=[],
                    help="file of matrix items (one or more a line; '#' starts a comment)")
    ap.add_argument("--jobs", type=int, default=1, metavar="N", help="runs at once (default 1)")
    ap.add_argument("--nice", type=int, default=19, metavar="N", help="nice level (default 19)")
    ap.add_argument("--only", metavar="REGEX",
                    help="run only the items (as SCENE:WxH:SPP:CONFIG) that this regex searches")
    ap.add_argument("--timeout", type=float, default=0, metavar="S",
                    help="kill a run after S seconds (default: no limit)")
    ap.add_argument("--retries", type=int, default=1, metavar="N",
                    help="run an item again, up to N times, if it did not end with status ok "
                         "(every attempt gets a CSV row; default 1)")
    ap.add_argument("--versions", metavar="K=V,...",
                    help="tool commits if ROOT/VERSIONS is missing: vulkan_sim=...,mesa=...,rtiv=...")
    ap.add_argument("--keep-runs", action="store_true",
                    help="keep the run directories of successful runs (default: delete them)")
    ap.add_argument("--dry-run", action="store_true", help="list what would run, run nothing")
    ap.add_argument("items", nargs="*", metavar="MATRIX", help="SCENE:WxH:SPP:CONFIG")
    args = ap.parse_args(argv)

    texts = list(args.items)
    for path in args.matrix:
        with open(path, encoding="utf-8") as f:
            for line in f:
                texts += line.split("#", 1)[0].split()
    try:
        items = [Item(t) for t in texts]
    except ValueError as e:
        ap.error(str(e))
    if args.only:
        items = [i for i in items if re.search(args.only, i.text)]
    seen, unique = set(), []
    for i in items:
        if i.key() not in seen:
            seen.add(i.key())
            unique.append(i)
    items = unique
    if not items:
        ap.error("no matrix items")

    args.vsim = os.path.abspath(args.vsim)
    args.scenes = os.path.abspath(args.scenes)
    args.out = os.path.abspath(args.out)
    check_root(args.vsim)
    for i in items:
        sc = SCENES[i.scene]
        subs = [s[1] for s in sc.get("models", {}).values() if s[0] == "link"]
        subs += [sc["folder"][1]] if "folder" in sc else []
        subs += {"bunny": ["bunny"], "ref": ["dragon"]}.get(i.scene, [])
        for s in subs:
            if not os.path.isdir(os.path.join(args.scenes, s)):
                sys.exit(f"scene {i.scene}: {os.path.join(args.scenes, s)} is missing")

    os.makedirs(args.out, exist_ok=True)
    csvfile = Csv(os.path.join(args.out, "reference.csv"))
    done = csvfile.done()
    todo = [i for i in items if i.key() not in done]
    log(f"{len(items)} items, {len(items) - len(todo)} already done, {len(todo)} to run "
        f"(jobs {args.jobs}, nice {args.nice})")
    if args.dry_run:
        for i in items:
            print(("done  " if i.key() in done else "run   ") + i.text)
        return 0
    if not todo:
        return 0
    versions = read_versions(args.vsim, args.versions)
    runner = Runner(args, versions, csvfile)
    runner.generate_models({i.scene for i in todo})

    # SIGINT and SIGTERM stop the matrix: the simulations this script started are terminated
    # (a background job inherits SIGINT ignored, so both are installed explicitly)
    def on_signal(signum, frame):
        raise KeyboardInterrupt
    signal.signal(signal.SIGINT, on_signal)
    signal.signal(signal.SIGTERM, on_signal)

    failures = 0
    pool = concurrent.futures.ThreadPoolExecutor(max_workers=max(1, args.jobs))
    try:
        futures = [pool.submit(runner.run, i) for i in todo]
        for fut in concurrent.futures.as_completed(futures):
            try:
                row = fut.result()
            except Exception as e:  # a broken run directory etc.: report, keep going
                log(f"error: {e!r}")
                failures += 1
                continue
            if row and row["status"] != "ok":
                failures += 1
    except KeyboardInterrupt:
        log("interrupted: stopping the running simulations")
        runner.stopping = True
        pool.shutdown(wait=False, cancel_futures=True)
        runner.kill_all()
        pool.shutdown(wait=True)  # the workers record the killed runs (status failed)
        return 130
    pool.shutdown()
    log(f"finished: {failures} run(s) failed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
