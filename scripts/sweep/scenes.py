"""What the experiment scripts share: the scenes our sweeps run on (name -> rtsim scene
arguments; {shared} is substituted by the worker with the folder of the shared scenes), their
command line, and the manifest writer."""
import argparse
import json

SCENES = {
    "wknd": "--scene wknd",
    "cornell": "--scene cornell",
    "ship": "--scene ship --assets {shared}/ship",
    "bunny": "--scene bunny --assets {shared}/bunny",
    "ref": "--scene ref --assets {shared}/dragon",
    "bath": "--scene bath --assets {shared}/bath",
    "sprng": "--scene sprng --assets {shared}/sprng",
    "party": "--scene party --assets {shared}/party",
}


def arguments(description, extra=None, size=128):
    """MANIFEST [--size N] [--spp N] [--scenes a,b,...] plus `extra(parser)` options; checks scenes.
    `size`: the default frame size."""
    ap = argparse.ArgumentParser(description=description)
    ap.add_argument("manifest")
    ap.add_argument("--size", type=int, default=size)
    ap.add_argument("--spp", type=int, default=2)
    ap.add_argument("--scenes", default=",".join(SCENES))
    if extra:
        extra(ap)
    a = ap.parse_args()
    a.scene_list = [s for s in a.scenes.split(",") if s]
    for s in a.scene_list:
        if s not in SCENES:
            raise SystemExit(f"experiments: unknown scene '{s}' (known: {', '.join(SCENES)})")
    return a


def write_manifest(a, runs, **meta):
    """One line per (run, scene): id EXPERIMENT/SCENE, rtsim arguments, output path; and the
    sweep's parameters beside it for the report."""
    with open(a.manifest + ".meta.json", "w") as f:
        json.dump({"size": a.size, "spp": a.spp, "scenes": a.scene_list, **meta}, f)
    with open(a.manifest, "w") as f:
        f.write("id\targs\toutput\n")
        for eid, args in runs:
            for s in a.scene_list:
                f.write(f"{eid}/{s}\t{SCENES[s]} {args.strip()}\t{eid}/{s}.json\n")
