"""What the report scripts share: reading a sweep's results.csv, means, Markdown tables, and the
words of comparison, computed from the figures so that no verdict is written by hand."""
import csv
import json
import math
import pathlib


def load(results):
    """{(experiment, scene): row} of a results.csv, and the sweep's parameters."""
    results = pathlib.Path(results)
    data = {}
    with open(results) as f:
        for r in csv.DictReader(f):
            data[(r["experiment"], r["scene"])] = r
    meta_file = results.parent / "manifest.tsv.meta.json"
    meta = json.loads(meta_file.read_text()) if meta_file.exists() else {"size": 128, "spp": 2}
    return data, meta


def number(data, exp, scene, col):
    r = data.get((exp, scene))
    if not r or r.get(col, "") in ("", None):
        return None
    return float(r[col])


def geomean(xs):
    xs = [x for x in xs if x]
    return math.exp(sum(math.log(x) for x in xs) / len(xs)) if xs else float("nan")


def mean(xs):
    xs = [x for x in xs if x is not None]
    return sum(xs) / len(xs) if xs else float("nan")


class Markdown:
    def __init__(self):
        self.lines = []

    def p(self, s=""):
        self.lines.append(s)

    def table(self, header, rows):
        self.p("| " + " | ".join(header) + " |")
        self.p("|" + "---|" * len(header))
        for r in rows:
            self.p("| " + " | ".join(str(c) for c in r) + " |")
        self.p()

    def text(self):
        return "\n".join(self.lines) + "\n"


def side(x, ref=1.0, tol=0.005):
    """'above', 'below' or 'at' ref (within tol)."""
    if x is None or x != x:
        return "unknown"
    return "at" if abs(x - ref) <= tol else "above" if x > ref else "below"


def direction(ours, paper, ref=1.0, tol=0.005):
    """Whether ours lies on the same side of ref as the paper's figure."""
    a, b = side(ours, ref, tol), side(paper, ref, tol)
    if "unknown" in (a, b):
        return "no data"
    return "agrees" if a == b else "differs"


def rank(values):
    """Names ordered from largest to smallest value."""
    return [k for k, _ in sorted(values.items(), key=lambda kv: -kv[1])]


def order(ours, paper):
    """Whether the variants rank in the same order in ours and in the paper's figures (the keys
    both have)."""
    keys = [k for k in paper if k in ours and ours[k] == ours[k]]
    if len(keys) < 2:
        return "no data"
    return "agrees" if rank({k: ours[k] for k in keys}) == rank({k: paper[k] for k in keys}) else "differs"


def share_words(part, whole):
    """How large part is against whole, in words a reader checks at a glance."""
    if not whole or whole != whole or part != part:
        return "no data"
    f = part / whole
    for value, words in ((1 / 5, "a fifth"), (1 / 4, "a quarter"), (1 / 3, "a third"), (1 / 2, "half"), (2 / 3, "two thirds"),
                         (3 / 4, "three quarters"), (1.0, "all")):
        if abs(f - value) <= 0.04:
            return f"{words} ({100 * f:.0f} %)"
    return f"{100 * f:.0f} %"


def pct(x, digits=1):
    return "-" if x is None or x != x else f"{100 * x:.{digits}f} %"


def times(x, digits=3):
    return "-" if x is None or x != x else f"{x:.{digits}f}x"
