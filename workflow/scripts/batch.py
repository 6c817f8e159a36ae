#!/usr/bin/env python3
"""One data set of a batch, and the batch's summary (workflow/Snakefile).

  batch.py run --root R --build B --work-root W --data D --row ROW --log LOG
               [--jobs N] [--make-vars "VAR=value ..."]
      Runs `make -f pipeline.mk DATA=D all` into W/<name>/, writes the data
      set's row (ROW on success, ROW with .failed.json on failure, naming the
      stage that failed and its message), redraws the summary, and exits
      with make's status.
  batch.py summary --work-root W
      Redraws W/batch/summary.csv and W/batch/index.html from W/batch/rows/.

Standard library only: the compute nodes need nothing but Python 3.
"""
import argparse
import csv
import fcntl
import html
import io
import json
import os
import re
import shlex
import socket
import subprocess
import sys
import time

# "<program>: <kind>: <message>", the one line every stage prints when it fails.
STAGE_ERROR = re.compile(
    r"^([a-z][a-z-]*): (bad input|cannot write output|usage error|error): (.*)$")
COLUMNS = ["name", "status", "failed_stage", "message", "seconds", "slurm_job_id", "host",
           "ms_ssim", "ld", "cer", "pdf", "report", "data"]


def write_atomic(path, text):
    tmp = "%s.tmp-%d" % (path, os.getpid())
    with open(tmp, "w", encoding="utf-8") as f:
        f.write(text)
    os.replace(tmp, path)


def failure_of(log_text):
    """(stage, message) from a failed pipeline.mk run's output."""
    lines = [l.strip() for l in log_text.splitlines() if l.strip()]
    for line in reversed(lines):
        m = STAGE_ERROR.match(line)
        if m:
            return m.group(1), "%s: %s" % (m.group(2), m.group(3))
    for line in reversed(lines):
        if line.startswith("pipeline.mk: "):
            return "pipeline.mk", line[len("pipeline.mk: "):]
    for line in reversed(lines):
        if not line.startswith(("make", "gmake")):
            return "", line
    return "", lines[-1] if lines else "no output"


def read_json(path):
    try:
        with open(path, encoding="utf-8") as f:
            return json.load(f)
    except (OSError, ValueError):
        return None


def run(args):
    resolved = subprocess.run(
        [os.path.join(args.root, "scripts/data-dir"), args.root, args.work_root, "", args.data],
        capture_output=True, text=True).stdout.split()
    if len(resolved) != 3:
        sys.exit("batch: %s: not a data set" % args.data)
    _, name, work = resolved
    os.makedirs(os.path.dirname(args.log), exist_ok=True)
    command = (["make", "-f", os.path.join(args.root, "pipeline.mk"), "NO_BUILD=1",
                "BUILD=" + args.build, "WORK_ROOT=" + args.work_root, "DATA=" + args.data,
                "JOBS=%d" % args.jobs] + shlex.split(args.make_vars) + ["all"])
    start = time.time()
    with open(args.log, "w", encoding="utf-8") as log:
        log.write("$ %s\n" % " ".join(shlex.quote(c) for c in command))
        log.flush()
        status = subprocess.run(command, stdout=log, stderr=subprocess.STDOUT,
                                cwd=args.root).returncode
    row = {"name": name, "data": args.data, "work": work, "status": "ok" if status == 0 else "failed",
           "seconds": round(time.time() - start, 1), "exit": status,
           "slurm_job_id": os.environ.get("SLURM_JOB_ID", ""), "host": socket.gethostname(),
           "log": args.log}
    if status != 0:
        with open(args.log, encoding="utf-8", errors="replace") as f:
            row["failed_stage"], row["message"] = failure_of(f.read())
    metrics = read_json(os.path.join(work, "70_eval/metrics.json"))
    if metrics and isinstance(metrics.get("metrics"), dict):
        row["metrics"] = {k: metrics["metrics"].get(k) for k in ("ms_ssim", "ld", "cer")}
    pdf = read_json(os.path.join(work, "80_pdf/pdf.json"))
    if pdf:
        row["pdf"] = os.path.join(work, "80_pdf", pdf["files"]["pdf"])
        row["thumbnail"] = os.path.join(work, "80_pdf", pdf["files"]["image"])
    elif os.path.exists(os.path.join(work, "60_render/rectified.png")):
        row["thumbnail"] = os.path.join(work, "60_render/rectified.png")
    if os.path.exists(os.path.join(work, "report.html")):
        row["report"] = os.path.join(work, "report.html")
    failed_row = args.row[:-len(".json")] + ".failed.json"
    os.makedirs(os.path.dirname(args.row), exist_ok=True)
    text = json.dumps(row, indent=1) + "\n"
    if status == 0:
        write_atomic(args.row, text)
        if os.path.exists(failed_row):
            os.remove(failed_row)
    else:
        write_atomic(failed_row, text)
    summarize(args.work_root)
    print("batch: %s %s in %.0f s%s" % (name, row["status"], row["seconds"],
          "" if status == 0 else " (%s: %s)" % (row["failed_stage"], row["message"])),
          file=sys.stderr)
    return status


def load_rows(batch):
    rows = {}
    folder = os.path.join(batch, "rows")
    if not os.path.isdir(folder):
        return rows
    for f in sorted(os.listdir(folder)):
        if not f.endswith(".json"):
            continue
        path = os.path.join(folder, f)
        row = read_json(path)
        if not row or "name" not in row:
            continue
        row["_mtime"] = os.path.getmtime(path)
        old = rows.get(row["name"])
        if old is None or row["_mtime"] > old["_mtime"]:
            rows[row["name"]] = row
    return rows


def cells(row):
    m = row.get("metrics") or {}
    fmt = lambda v, spec: "" if v is None else spec % v
    return {"name": row["name"], "status": row["status"], "failed_stage": row.get("failed_stage", ""),
            "message": row.get("message", ""), "seconds": row["seconds"],
            "slurm_job_id": row.get("slurm_job_id", ""), "host": row.get("host", ""),
            "ms_ssim": fmt(m.get("ms_ssim"), "%.4f"), "ld": fmt(m.get("ld"), "%.2f"),
            "cer": fmt(m.get("cer"), "%.4f"), "pdf": row.get("pdf", ""),
            "report": row.get("report", ""), "data": row["data"]}


def index_html(batch, rows):
    def link(path, text):
        if not path:
            return ""
        return '<a href="%s">%s</a>' % (html.escape(os.path.relpath(path, batch)), text)
    out = ["<!DOCTYPE html><html lang=\"en\"><head><meta charset=\"utf-8\">",
           "<title>docunfold batch</title><style>body{font-family:sans-serif;margin:1.5em}"
           "table{border-collapse:collapse}td,th{border:1px solid #ccc;padding:4px 8px;"
           "vertical-align:top}.failed{background:#fde8e8}img{width:120px}</style></head><body>",
           "<h1>docunfold batch</h1><p>%d data sets: %d done, %d failed; updated %s.</p>" % (
               len(rows), sum(r["status"] == "ok" for r in rows.values()),
               sum(r["status"] != "ok" for r in rows.values()), time.strftime("%Y-%m-%d %H:%M:%S")),
           "<table><tr><th>data set</th><th>result</th><th>status</th><th>time s</th>"
           "<th>MS-SSIM</th><th>LD</th><th>CER</th><th>files</th></tr>"]
    for name in sorted(rows):
        row, c = rows[name], cells(rows[name])
        thumb = row.get("thumbnail", "")
        img = ('<img loading="lazy" src="%s" alt="%s">' % (
            html.escape(os.path.relpath(thumb, batch)), html.escape(name)) if thumb else "")
        status = "ok" if row["status"] == "ok" else "failed in <b>%s</b>: %s" % (
            html.escape(c["failed_stage"] or "?"), html.escape(c["message"]))
        out.append("<tr%s><td>%s<br><small>%s</small></td><td>%s</td><td>%s</td><td>%s</td>"
                   "<td>%s</td><td>%s</td><td>%s</td><td>%s %s %s</td></tr>" % (
                       "" if row["status"] == "ok" else ' class="failed"', html.escape(name),
                       html.escape(row["data"]), img, status, c["seconds"], c["ms_ssim"], c["ld"],
                       c["cer"], link(row.get("pdf"), "PDF"), link(row.get("report"), "report"),
                       link(row.get("log"), "log")))
    out.append("</table></body></html>\n")
    return "\n".join(out)


def summarize(work_root):
    batch = os.path.join(work_root, "batch")
    os.makedirs(batch, exist_ok=True)
    with open(os.path.join(batch, ".lock"), "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        rows = load_rows(batch)
        table = io.StringIO()
        writer = csv.DictWriter(table, fieldnames=COLUMNS)
        writer.writeheader()
        for name in sorted(rows):
            writer.writerow(cells(rows[name]))
        write_atomic(os.path.join(batch, "summary.csv"), table.getvalue())
        write_atomic(os.path.join(batch, "index.html"), index_html(batch, rows))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    sub = parser.add_subparsers(dest="command", required=True)
    r = sub.add_parser("run")
    for flag in ("--root", "--build", "--work-root", "--data", "--row", "--log"):
        r.add_argument(flag, required=True)
    r.add_argument("--jobs", type=int, default=2)
    r.add_argument("--make-vars", default="")
    s = sub.add_parser("summary")
    s.add_argument("--work-root", required=True)
    args = parser.parse_args()
    if args.command == "run":
        return run(args)
    summarize(args.work_root)
    return 0


if __name__ == "__main__":
    sys.exit(main())
