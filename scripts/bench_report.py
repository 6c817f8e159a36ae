"""Turns work/bench/<set>/timings.jsonl into bench/results.{json,md}."""
import datetime
import json
import os
import platform
import subprocess
import sys


def image_size(root, name):
    """Width x height of the first image of a sample, from its ground-truth cameras."""
    path = os.path.join(root, "samples", name, "ground_truth", "cameras.json")
    try:
        with open(path) as f:
            v = json.load(f)["views"]
        return "%dx%d" % (v[0]["width"], v[0]["height"]), len(v)
    except (OSError, KeyError, ValueError, IndexError):
        return "?", 0


def cpu_name():
    try:
        out = subprocess.run(["lscpu"], capture_output=True, text=True).stdout
        for line in out.splitlines():
            if line.startswith("Model name:"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def main(root, work, sets):
    rows = []
    for s in sets:
        size, views = image_size(root, s)
        timings = []
        path = os.path.join(work, s, "timings.jsonl")
        if os.path.exists(path):
            with open(path) as f:
                timings = [json.loads(line) for line in f if line.strip()]
        rows.append({"set": s, "image_size": size, "views": views, "stages": timings})
    stages = []
    for r in rows:
        for t in r["stages"]:
            if t["stage"] not in stages:
                stages.append(t["stage"])
    result = {
        "format": "docunfold.bench", "version": 1,
        "date": datetime.date.today().isoformat(),
        "machine": {"cpu": cpu_name(), "cores": os.cpu_count()},
        "sets": rows,
    }
    os.makedirs(os.path.join(root, "bench"), exist_ok=True)
    with open(os.path.join(root, "bench", "results.json"), "w") as f:
        json.dump(result, f, indent=1)
        f.write("\n")
    lines = ["# Benchmark results", "",
             "Made by `make -f pipeline.mk bench` on %s (%s, %d cores)." % (
                 result["date"], result["machine"]["cpu"], result["machine"]["cores"]),
             "Each stage runs from scratch; time is wall-clock seconds, memory is peak RSS.", "",
             "| set | images | " + " | ".join("%s s / MB" % s for s in stages) + " |",
             "|---|---|" + "---|" * len(stages)]
    for r in rows:
        cells = []
        for s in stages:
            t = [x for x in r["stages"] if x["stage"] == s]
            if not t:
                cells.append("–")
            else:
                t = t[-1]
                cells.append("%.1f / %.0f%s" % (t["seconds"], t["max_rss_mb"],
                                                 "" if t["exit"] == 0 else " (exit %d)" % t["exit"]))
        lines.append("| %s | %d × %s | %s |" % (r["set"], r["views"], r["image_size"], " | ".join(cells)))
    with open(os.path.join(root, "bench", "results.md"), "w") as f:
        f.write("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2], sys.argv[3:])
