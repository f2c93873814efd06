#!/usr/bin/python3
"""Snakemake's --cluster-status for SLURM: prints running, success or failed
for the job id Snakemake got from `sbatch --parsable`.

Asks scontrol first (the controller keeps finished jobs MinJobAge seconds,
300 by default, and Snakemake asks every few seconds), then sacct (sites with
accounting). A job neither knows is reported failed: Snakemake then reruns or
stops instead of waiting forever.
"""
import subprocess
import sys

RUNNING = {"PENDING", "CONFIGURING", "RUNNING", "COMPLETING", "SUSPENDED", "REQUEUED", "REQUEUE_FED",
           "REQUEUE_HOLD", "RESIZING", "SIGNALING", "STAGE_OUT", "PREEMPTED", "SPECIAL_EXIT"}

jobid = sys.argv[1].split(";")[0]  # --parsable prints "id" or "id;cluster"


def state_from_scontrol():
    r = subprocess.run(["scontrol", "show", "job", "-o", jobid], capture_output=True, text=True)
    if r.returncode != 0:
        return None
    for field in r.stdout.split():
        if field.startswith("JobState="):
            return field.split("=", 1)[1]
    return None


def state_from_sacct():
    try:
        r = subprocess.run(["sacct", "-n", "-X", "-P", "-j", jobid, "-o", "State"], capture_output=True, text=True)
    except FileNotFoundError:
        return None
    lines = r.stdout.split()
    # "CANCELLED by 0" -> CANCELLED
    return lines[0].split()[0] if r.returncode == 0 and lines else None


state = state_from_scontrol() or state_from_sacct()
if state is None:
    print(f"slurm_status: job {jobid} unknown to scontrol and sacct", file=sys.stderr)
    print("failed")
elif state == "COMPLETED":
    print("success")
elif state in RUNNING:
    print("running")
else:  # FAILED, TIMEOUT, OUT_OF_MEMORY, CANCELLED, NODE_FAIL, BOOT_FAIL, DEADLINE
    print("failed")
