"""Writes bench/results.json (docunfold.bench) and bench/results.md from the
work directories scripts/bench.sh filled:

  <work>/<set>/timings.jsonl       pipeline stages (scripts/stage-timer lines)
  <work>/<set>/bench/timings.jsonl making ("make:<row>") and evaluating
                                   ("evaluate:<row>") each row
  <work>/<set>/bench/rows.tsv      method, status, image, metrics file, mesh dir, note
  <work>/<set>/bench/pipeline.exit exit code of the pipeline run
  <work>/<set>/70_eval/front_end.json  the front end against the truth
                                   (evaluate --front-end)

usage: bench_report.py --root R --work W --out O [--frontend F] [--eval-flags S] NAME=DATA_DIR...
"""
import argparse
import datetime
import json
import math
import os
import platform
import re
import struct
import subprocess

# Pipeline stages in chain order (names as pipeline.mk's TIMER records them).
STAGE_ORDER = ["truth-frontend", "sfm", "segment-boundary", "densify", "detect-features", "init-mesh",
               "optimize", "render", "pdf", "evaluate"]
# Figures of a row, in table order: (key in metrics, column title, format).
FIGURES = [("ms_ssim", "MS-SSIM ↑", "%.4f"), ("ld", "LD ↓", "%.2f"), ("li_d", "Li-D ↓", "%.2f"),
           ("cer", "CER ↓", "%.4f"), ("wer", "WER ↓", "%.4f"),
           ("surface_mean_pct", "surface mean % ↓", "%.3f"),
           ("isometry_mean", "isometry ↓", "%.4f"),
           ("ms_ssim_registered", "MS-SSIM one affine map away ↑", "%.4f")]
ROW_ORDER = ["homography", "oracle", "oracle-seen", "oracle-multiview", "docunfold",
             "docunfold-reference", "docunfold-init", "docunfold-nofeatures",
             "docunfold-boundary", "docunfold-from-truth", "oracle-deshaded",
             "docunfold-deshaded"]


def read_jsonl(path):
    out = []
    if os.path.exists(path):
        with open(path) as f:
            for line in f:
                line = line.strip()
                if line:
                    try:
                        out.append(json.loads(line))
                    except ValueError:
                        pass
    return out


def image_header_size(path):
    """(width, height) of a PNG or JPEG from its header, or None."""
    try:
        with open(path, "rb") as f:
            head = f.read(26)
            if head[:8] == b"\x89PNG\r\n\x1a\n":
                return struct.unpack(">II", head[16:24])
            if head[:2] != b"\xff\xd8":
                return None
            f.seek(2)
            while True:
                marker = f.read(2)
                if len(marker) < 2 or marker[0] != 0xFF:
                    return None
                if marker[1] in (0xD8, 0x01) or 0xD0 <= marker[1] <= 0xD7:
                    continue
                length = struct.unpack(">H", f.read(2))[0]
                if marker[1] in (0xC0, 0xC1, 0xC2, 0xC3, 0xC5, 0xC6, 0xC7, 0xC9, 0xCA, 0xCB,
                                 0xCD, 0xCE, 0xCF):
                    h, w = struct.unpack(">xHH", f.read(5))
                    return w, h
                f.seek(length - 2, 1)
    except (OSError, struct.error):
        return None


def describe_images(data):
    """(number of photos, "1600x1200" or, for mixed sizes, "4 × 1600x1200 + 1 × 8000x6000")."""
    images = sorted(n for n in os.listdir(os.path.join(data, "images"))
                    if n.lower().endswith((".jpg", ".jpeg", ".png", ".tif", ".tiff")))
    sizes = {}
    for name in images:
        size = image_header_size(os.path.join(data, "images", name))
        key = "%dx%d" % size if size else "?"
        sizes[key] = sizes.get(key, 0) + 1
    if len(sizes) <= 1:
        return len(images), (next(iter(sizes)) if sizes else "?")
    return len(images), " + ".join("%d × %s" % (n, k) for k, n in sizes.items())


def cpu_name():
    try:
        out = subprocess.run(["lscpu"], capture_output=True, text=True).stdout
        for line in out.splitlines():
            if line.startswith("Model name:"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def git_commit(root):
    try:
        rev = subprocess.run(["git", "-C", root, "rev-parse", "--short", "HEAD"],
                             capture_output=True, text=True).stdout.strip()
        dirty = subprocess.run(["git", "-C", root, "status", "--porcelain", "--untracked-files=no"],
                               capture_output=True, text=True).stdout.strip()
        return rev + ("+modified" if dirty else "") if rev else "unknown"
    except OSError:
        return "unknown"


def program_version(root):
    try:
        with open(os.path.join(root, "CMakeLists.txt")) as f:
            for line in f:
                if line.startswith("project(") and "VERSION" in line:
                    return line.split("VERSION")[1].split()[0]
    except OSError:
        pass
    return "unknown"


def finite(v):
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def summarize_timing(entries):
    """Several commands of one row (optimize + render) add up."""
    if not entries:
        return None
    return {"seconds": round(sum(e["seconds"] for e in entries), 2),
            "max_rss_mb": round(max(e["max_rss_mb"] for e in entries), 1),
            "exit": next((e["exit"] for e in entries if e["exit"] != 0), 0)}


def collect_set(name, data, work):
    set_work = os.path.join(work, name)
    views, size = describe_images(data)
    stages = read_jsonl(os.path.join(set_work, "timings.jsonl"))
    row_timings = read_jsonl(os.path.join(set_work, "bench", "timings.jsonl"))
    exit_path = os.path.join(set_work, "bench", "pipeline.exit")
    pipeline_exit = None
    if os.path.exists(exit_path):
        with open(exit_path) as f:
            pipeline_exit = int(f.read().strip() or 0)
    rows = []
    tsv = os.path.join(set_work, "bench", "rows.tsv")
    if os.path.exists(tsv):
        with open(tsv) as f:
            for line in f:
                fields = line.rstrip("\n").split("\t")
                if len(fields) < 6:
                    continue
                method, status, image, metrics_file, mesh_dir, note = fields[:6]
                row = {"method": method, "status": status}
                if image:
                    row["image"] = image
                if mesh_dir:
                    row["mesh_dir"] = mesh_dir
                if note:
                    row["note"] = note
                row["make"] = summarize_timing(
                    [t for t in row_timings if t["stage"] == "make:" + method])
                row["evaluate"] = summarize_timing(
                    [t for t in row_timings if t["stage"] == "evaluate:" + method])
                row["metrics"] = None
                if metrics_file and os.path.exists(metrics_file):
                    row["metrics_file"] = metrics_file
                    with open(metrics_file) as mf:
                        doc = json.load(mf)
                    row["metrics"] = {k: v for k, v in doc.get("metrics", {}).items()}
                rows.append(row)
    rows.sort(key=lambda r: (ROW_ORDER.index(r["method"]) if r["method"] in ROW_ORDER
                             else len(ROW_ORDER), r["method"]))
    failed_stage = next((s["stage"] for s in stages if s.get("exit", 0) != 0), None)
    front_end = None
    fe_path = os.path.join(set_work, "70_eval", "front_end.json")
    if os.path.exists(fe_path):
        with open(fe_path) as f:
            doc = json.load(f)
        front_end = {k: doc.get(k) for k in ("reference", "boundary", "features")}
        front_end["evaluate"] = summarize_timing(
            [t for t in row_timings if t["stage"] == "evaluate:front-end"])
    pdf = None
    pdf_path = os.path.join(set_work, "70_eval", "pdf.json")
    if os.path.exists(pdf_path):
        with open(pdf_path) as f:
            doc = json.load(f)
        text = doc.get("text", {})
        pdf = {"pages": doc.get("pages"), "page": doc.get("page"),
               "words_found": text.get("words_found"),
               "cer_reading_order": text.get("cer_reading_order"),
               "evaluate": summarize_timing(
                   [t for t in row_timings if t["stage"] == "evaluate:pdf"])}
    variant_file = os.path.join(data, "VARIANT")
    variant_of = open(variant_file).read().strip() if os.path.exists(variant_file) else None
    return {"name": name, "path": data, "variant_of": variant_of, "views": views,
            "image_size": size,
            "has_ground_truth": os.path.exists(os.path.join(data, "ground_truth", "flat.png")),
            "pipeline": {"exit": pipeline_exit, "failed_stage": failed_stage},
            "stages": stages, "rows": rows, "front_end": front_end, "pdf": pdf}


def collect_solvers(work, name):
    """Gauss-Newton vs L-BFGS on one set: per solver the wall time, the final
    F of each round, and the time at which the last round first reached the
    worse of the two final Fs (the F both reach)."""
    logs = {}
    for solver in ("gn", "lbfgs"):
        path = os.path.join(work, name, "bench", "solver_" + solver, "log.json")
        if not os.path.exists(path):
            return None
        with open(path) as f:
            logs[solver] = json.load(f)
    finals = {s: l["rounds"][-1]["iterations"][-1]["F"] for s, l in logs.items()}
    target = max(finals.values())
    out = {"set": name, "target_F": target, "solvers": []}
    for solver, log in logs.items():
        last = log["rounds"][-1]["iterations"]
        reached = next((it["seconds"] for it in last if it["F"] <= target * (1 + 1e-9)), None)
        out["solvers"].append({
            "solver": solver, "method": log["rounds"][-1]["solver"].get("method"),
            "seconds": log["seconds"], "final_F": finals[solver],
            "seconds_to_target": reached,
            "iterations": sum(len(r["iterations"]) for r in log["rounds"]),
            "round_F": [r["iterations"][-1]["F"] for r in log["rounds"]]})
    return out


def summarize(sets):
    # A variant of another set (phone-photos: the same page, its photos changed)
    # would count that page twice.
    sets = [s for s in sets if not s.get("variant_of")]
    methods = []
    for s in sets:
        for r in s["rows"]:
            if r["status"] == "ok" and r["method"] not in methods:
                methods.append(r["method"])
    methods.sort(key=lambda m: (ROW_ORDER.index(m) if m in ROW_ORDER else len(ROW_ORDER), m))
    summary = []
    for m in methods:
        rows = [r for s in sets for r in s["rows"] if r["method"] == m and r["status"] == "ok"]
        means = {}
        for key, _, _ in FIGURES:
            values = [r["metrics"][key] for r in rows if r["metrics"] and finite(r["metrics"].get(key))]
            means[key] = sum(values) / len(values) if values else None
            means[key + "_sets"] = len(values)
        summary.append({"method": m, "sets": len(rows), "means": means})
    return summary


def fmt(v, f):
    return f % v if finite(v) else "–"


def mark(value, ok, f):
    """A figure with ✗ after it when it misses the front end's target."""
    return fmt(value, f) + ("" if ok or not finite(value) else " ✗")


def front_end_markdown(sets):
    measured = [s for s in sets if s.get("front_end")]
    if not measured:
        return []
    lines = ["", "## Front end against the ground truth", "",
             "segment-boundary and detect-features in the reference view sfm picked "
             "(`evaluate --front-end`, 70_eval/front_end.json), the truth moved into "
             "reference.png by sfm's undistortion. ✗ marks a figure short of the front end's "
             "targets (IoU ≥ 0.97; every visible true corner within 1 % of the page diagonal; real "
             "sides on the true edge and covering it; a cut page has a side flagged not real, "
             "a whole page none; precision ≥ 0.95; recall ≥ 0.5 on text pages and tables). "
             "Corners and sides are not judged where a true corner is hidden by a fold.", "",
             "| set | reference | IoU | worst corner % diag | real sides off edge px (p95 / max) "
             "| edge covered | not real / page cut | precision (text, edge) | recall (text, rules) "
             "| segments text / edge |",
             "|---|---|---:|---:|---:|---:|---|---:|---:|---:|"]
    held = {"boundary": 0, "features": 0}
    counted = {"boundary": 0, "features": 0}
    for s in measured:
        fe = s["front_end"]
        b, f = fe.get("boundary") or {}, fe.get("features") or {}
        cells = [s["name"], fe.get("reference") or "?"]
        if "iou" in b:
            h = b["holds"]
            counted["boundary"] += 1
            held["boundary"] += all(h.values())
            cells += [mark(b["iou"], h["iou"], "%.4f"),
                      mark(100 * b["worst_corner_fraction"], h["corners"], "%.2f") +
                      (" (hidden)" if b["corner_hidden"] else ""),
                      mark(b["real_off_edge_px"], h["sides"], "%.1f") + " / " +
                      fmt(b["real_off_edge_max_px"], "%.1f"),
                      fmt(b["edge_recall"], "%.3f"),
                      "%d / %s%s" % (b["sides_not_real"], "yes" if b["page_cut"] else "no",
                                     "" if h["cut_flags"] else " ✗")]
        else:
            cells += ["–"] * 5
        if "precision" in f:
            h = f["holds"]
            counted["features"] += 1
            held["features"] += all(h.values())
            cells += ["%s (%s, %s)" % (mark(f["precision"], h["precision"], "%.3f"),
                                       fmt(f["precision_text"], "%.3f"),
                                       fmt(f["precision_edge"], "%.3f")),
                      "%s (%s, %s)%s" % (mark(f["recall"], h["recall"], "%.3f"),
                                         fmt(f["recall_text"], "%.3f"),
                                         fmt(f["recall_rule"], "%.3f"),
                                         "" if f["recall_required"] else " ·"),
                      "%d / %d" % (f["text_segments"], f["edge_segments"])]
        else:
            cells += ["–"] * 3
        lines.append("| " + " | ".join(cells) + " |")
    lines += ["", "· recall only measured (receipt, poster). Every boundary figure holds on "
              "%d of %d sets, both feature figures on %d of %d." % (
                  held["boundary"], counted["boundary"], held["features"], counted["features"])]
    return lines


def pdf_markdown(sets):
    measured = [s for s in sets if s.get("pdf")]
    if not measured:
        return []
    lines = ["", "## The searchable PDF", "",
             "80_pdf/<set>.pdf read back as a viewer reads it (`evaluate --pdf`, "
             "70_eval/pdf.json): words found = share of ground_truth/text.txt's words that "
             "pdftotext's text holds, in any order (what a search finds: a word is what "
             "whitespace separates, less the punctuation at its ends); CER of that text in "
             "its reading order (what a copy gives; a receipt's dashed separators, which the "
             "PDF does not spell out, count against it); the page's size against the true "
             "page's (✗: a side more than 1 % off).", "",
             "| set | words found ↑ | CER in reading order ↓ | page mm | true mm |",
             "|---|---:|---:|---|---|"]
    found = []
    for s in measured:
        p = s["pdf"]
        page = p.get("page") or {}
        err = page.get("size_error")
        true = ("%.0f × %.0f" % (page["true_width_mm"], page["true_height_mm"])
                if finite(page.get("true_width_mm")) else "–")
        lines.append("| %s | %s | %s | %.0f × %.0f%s | %s |" % (
            s["name"], fmt(p["words_found"], "%.3f"), fmt(p["cer_reading_order"], "%.3f"),
            page.get("width_mm", 0), page.get("height_mm", 0),
            " ✗" if finite(err) and err > 0.01 else "", true))
        if finite(p["words_found"]) and not s.get("variant_of"):
            found.append(p["words_found"])
    if found:
        lines += ["", "Mean words found over %d sets: %.3f." % (len(found), sum(found) / len(found))]
    return lines


def markdown(result):
    sets, lines = result["sets"], []
    m = result["machine"]
    lines += ["# Benchmark results", "",
              "Made by `make -f pipeline.mk bench` on %s (%s, %d cores), commit %s." % (
                  result["date"], m["cpu"], m["cores"], result["commit"]),
              ("Front end: **ground truth** (`truth-frontend` wrote 10_sfm/ and 20_boundary/; "
               "sfm and segment-boundary did not run)." if result["frontend"] == "truth" else
               "Front end: the pipeline's own (sfm, segment-boundary)."),
              "",
              "MS-SSIM as on the DocUNet benchmark (ground truth at 598 400 pixels); LD and Li-D "
              "from DeepFlow (a stand-in for SIFT flow), in pixels at half that size; CER and WER "
              "of Tesseract (eng) on the result%s against Tesseract on flat.png; surface mean "
              "distance of M to the true surface in %% of the page diagonal; isometry = mean "
              "relative edge-length error between M and M'; MS-SSIM one affine map away = "
              "MS-SSIM after registering the result to flat.png by the best single affine map "
              "(evaluate `--registered`): what is left when the crop's sides and the page's scale "
              "are forgiven. "
              "Rows: `homography` = reference photo warped by the 4 page corners (scanner app), turned the way render turned docunfold's page; "
              "`oracle` = reference photo textured through the true surface and camera (ceiling "
              "for one-view texturing); `oracle-seen` = the oracle cropped to the part of the page "
              "some photo sees (the same image where the page is seen whole; the ceiling for a "
              "method that has only the photos when a page is cut off in all of them); "
              "`oracle-multiview` = the true surface textured from every photo through the true "
              "cameras by render's texture fusion, cropped like `oracle-seen` (the ceiling for "
              "texturing from all the photos); `docunfold` = 60_render/rectified.png (texture fusion); "
              "`docunfold-reference` = the same meshes textured from the reference photo alone "
              "(render `--texture reference`, the paper's way); `docunfold-from-truth` = optimize "
              "started from the true surface on init-mesh's grid in sfm's frame, then render "
              "(what optimize itself loses); `-deshaded` = "
              "the same with the light's shading divided out (render/baseline `--shading "
              "remove`): compare `docunfold-deshaded` with `oracle-deshaded`, not with "
              "`oracle`." % (
                  " resized to flat.png's size" if "--ocr-at-truth-size" in result["producer"]
                  ["options"]["eval_flags"] else " as it is"),
              "Evaluate flags: `%s`." % (result["producer"]["options"]["eval_flags"] or "(none)"),
              ""]
    lines += ["## Quality", "",
              "| set | method | " + " | ".join(t for _, t, _ in FIGURES) + " |",
              "|---|---|" + "---:|" * len(FIGURES)]
    notes = []
    for s in sets:
        for r in s["rows"]:
            if r["status"] == "ok":
                cells = [fmt(r["metrics"].get(k), f) for k, _, f in FIGURES]
                lines.append("| %s | %s | %s |" % (s["name"], r["method"], " | ".join(cells)))
            elif r["status"] == "failed":
                lines.append("| %s | %s | failed: %s |" % (
                    s["name"], r["method"], r.get("note", "").replace("|", "/")) +
                    " |" * (len(FIGURES) - 1))
            else:
                notes.append((r["method"], r.get("note", ""), s["name"]))
    variants = [s["name"] for s in sets if s.get("variant_of")]
    lines += ["", "**Means per method** (over the sets where the row exists%s):" % (
        "; not over %s, made from another set's photos" % ", ".join(variants) if variants else ""),
        "",
              "| method | sets | " + " | ".join(t for _, t, _ in FIGURES) + " |",
              "|---|---:|" + "---:|" * len(FIGURES)]
    for e in result["summary"]:
        lines.append("| %s | %d | %s |" % (e["method"], e["sets"], " | ".join(
            fmt(e["means"][k], f) for k, _, f in FIGURES)))
    lines.append("")
    lines.append("Summary: " + "; ".join(
        "%s %s" % (e["method"], ", ".join("%s %s" % (t.split()[0], fmt(e["means"][k], f))
                                          for k, t, f in FIGURES[:4] if finite(e["means"][k])))
        for e in result["summary"]) + ".")
    if notes:
        # One entry per method and reason, naming the sets unless it is all.
        grouped = {}
        for method, note, name in notes:
            grouped.setdefault((method, note), []).append(name)
        lines += ["", "Rows not made: " + "; ".join(
            "%s: %s (%s)" % (method, note, "all sets" if len(names) == len(sets) and len(sets) > 1
                             else ", ".join(names))
            for (method, note), names in grouped.items()) + "."]

    lines += front_end_markdown(sets)
    lines += pdf_markdown(sets)

    stages = []
    for s in sets:
        for t in s["stages"]:
            if t["stage"] not in stages:
                stages.append(t["stage"])
    stages.sort(key=lambda x: STAGE_ORDER.index(x) if x in STAGE_ORDER else len(STAGE_ORDER))
    lines += ["", "## Time and memory per stage", "",
              "Wall-clock seconds / peak RSS in MB of each pipeline stage, from scratch. Stages "
              "not implemented yet are absent.", ""]
    if stages:
        lines += ["| set | images | " + " | ".join(stages) + " | total s |",
                  "|---|---|" + "---:|" * (len(stages) + 1)]
        for s in sets:
            cells, total = [], 0.0
            for st in stages:
                t = [x for x in s["stages"] if x["stage"] == st]
                if not t:
                    cells.append("–")
                    continue
                t = t[-1]
                total += t["seconds"]
                cells.append("%.1f / %.0f%s" % (t["seconds"], t["max_rss_mb"],
                                                 "" if t["exit"] == 0 else " (exit %d)" % t["exit"]))
            images = (s["image_size"] if "×" in s["image_size"]
                      else "%d × %s" % (s["views"], s["image_size"]))
            lines.append("| %s | %s | %s | %.1f |" % (s["name"], images, " | ".join(cells), total))
    else:
        lines.append("(no pipeline stage ran)")
    failed = [s for s in sets if s["pipeline"]["exit"]]
    for s in failed:
        lines.append("")
        lines.append("%s: the pipeline stopped with exit %s%s (log: %s)." % (
            s["name"], s["pipeline"]["exit"],
            " in " + s["pipeline"]["failed_stage"] if s["pipeline"]["failed_stage"] else "",
            os.path.join(result["work"], s["name"], "bench", "pipeline.log")))

    sv = result.get("solvers")
    if sv:
        lines += ["", "## Gauss-Newton against L-BFGS (optimize on %s)" % sv["set"], "",
                  "Both solvers on the same inputs with the default schedule, nothing else "
                  "running. *to F\\** = wall time at which the last round first reached "
                  "F\\* = %.4g, the worse of the two final values." % sv["target_F"], "",
                  "| solver | method (last round) | total s | outer iterations | final F | "
                  "to F\\* s | F after each round |", "|---|---|---:|---:|---:|---:|---|"]
        for s in sv["solvers"]:
            lines.append("| %s | %s | %.1f | %d | %.4g | %s | %s |" % (
                s["solver"], s["method"], s["seconds"], s["iterations"], s["final_F"],
                fmt(s["seconds_to_target"], "%.1f"),
                ", ".join("%.3g" % f for f in s["round_F"])))

    lines += ["", "## Making and evaluating each row", "",
              "| set | method | make s / MB | evaluate s / MB |", "|---|---|---:|---:|"]
    for s in sets:
        for r in s["rows"]:
            if r["status"] == "skipped":
                continue
            mk = r["make"]
            ev = r["evaluate"]
            lines.append("| %s | %s | %s | %s |" % (
                s["name"], r["method"],
                "%.1f / %.0f" % (mk["seconds"], mk["max_rss_mb"]) if mk else "(pipeline)",
                "%.1f / %.0f" % (ev["seconds"], ev["max_rss_mb"]) if ev else "–"))
    return "\n".join(lines) + "\n"


def kept_sections(path):
    """Sections other scripts own in results.md (scripts/bench-batch's, between
    <!-- <name>:begin --> and <!-- <name>:end -->), carried over as they are."""
    if not os.path.exists(path):
        return ""
    text = open(path, encoding="utf-8").read()
    pattern = r"\n<!-- ([a-z-]+):begin -->\n.*?\n<!-- \1:end -->\n"
    return "".join(m.group(0) for m in re.finditer(pattern, text, re.S))


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--root", required=True)
    p.add_argument("--work", required=True)
    p.add_argument("--out", required=True)
    p.add_argument("--frontend", default="pipeline", choices=["pipeline", "truth"])
    p.add_argument("--eval-flags", default="")
    p.add_argument("--solver-set", default=None,
                   help="set whose bench/solver_{gn,lbfgs}/log.json compare the solvers")
    p.add_argument("sets", nargs="+", help="NAME=DATA_DIR")
    a = p.parse_args()
    sets = []
    for spec in a.sets:
        name, data = spec.split("=", 1)
        sets.append(collect_set(name, data, a.work))
    result = {
        "format": "docunfold.bench", "version": 1,
        "producer": {"program": "docunfold", "stage": "bench", "version": program_version(a.root),
                     "options": {"frontend": a.frontend, "eval_flags": a.eval_flags,
                                 "sets": [s["path"] for s in sets]}},
        "date": datetime.date.today().isoformat(),
        "commit": git_commit(a.root),
        "machine": {"cpu": cpu_name(), "cores": os.cpu_count()},
        "frontend": a.frontend,
        "work": a.work,
        "sets": sets,
        "summary": summarize(sets),
    }
    if a.solver_set:
        solvers = collect_solvers(a.work, a.solver_set)
        if solvers:
            result["solvers"] = solvers
    os.makedirs(a.out, exist_ok=True)
    # NaN never reaches JSON: evaluate writes null for figures it lacks.
    with open(os.path.join(a.out, "results.json.tmp"), "w") as f:
        json.dump(result, f, indent=1, ensure_ascii=False, allow_nan=False)
        f.write("\n")
    os.replace(os.path.join(a.out, "results.json.tmp"), os.path.join(a.out, "results.json"))
    text = markdown(result) + kept_sections(os.path.join(a.out, "results.md"))
    with open(os.path.join(a.out, "results.md.tmp"), "w") as f:
        f.write(text)
    os.replace(os.path.join(a.out, "results.md.tmp"), os.path.join(a.out, "results.md"))
    print(text, end="")


if __name__ == "__main__":
    main()
