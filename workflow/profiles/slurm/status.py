#!/usr/bin/env python3
"""Snakemake's --cluster-status for Slurm: prints success, running or failed
for the job id given, from `scontrol show job` (no accounting database
needed), or from sacct where scontrol has forgotten the job."""
import subprocess
import sys

RUNNING = {"PENDING", "CONFIGURING", "RUNNING", "COMPLETING", "SUSPENDED", "REQUEUED",
           "RESIZING", "SIGNALING", "STAGE_OUT", "REQUEUE_HOLD", "REQUEUE_FED"}


def state(job):
    out = subprocess.run(["scontrol", "show", "job", "-o", job], capture_output=True, text=True)
    for field in out.stdout.split():
        if field.startswith("JobState="):
            return field.split("=", 1)[1]
    out = subprocess.run(["sacct", "-n", "-X", "-P", "-o", "State", "-j", job],
                         capture_output=True, text=True)
    lines = out.stdout.split()
    return lines[0].split()[0] if out.returncode == 0 and lines else ""


s = state(sys.argv[1])
print("success" if s == "COMPLETED" else "running" if s in RUNNING or s == "" else "failed")
