#!/usr/bin/env python3
"""Checks the Kubernetes manifests as far as can be done without a cluster: each validates,
strictly, against the Job and PersistentVolumeClaim schemas of Kubernetes (kubernetes-validate,
the API's own OpenAPI schemas), and the command a pod runs is the Slurm task's: the same `twin
montecarlo` subcommand, study, flags in the same order, and the same shard count.

Usage (from the repository's root): python3 studies/cluster/check-k8s.py
"""
import re
import shlex
import subprocess
import sys

import yaml

MANIFESTS = ["studies/cluster/k8s-table-5-1.yaml", "studies/cluster/k8s-table-5-1-merge.yaml"]


def fail(message):
    print(f"check-k8s: {message}", file=sys.stderr)
    sys.exit(1)


def flags(words):
    """The `twin` command's words after the binary, with each shell variable's text kept."""
    start = next(i for i, w in enumerate(words) if w.endswith("twin"))
    return words[start + 1:]


result = subprocess.run(
    ["kubernetes-validate", "--strict", "--quiet", *MANIFESTS], capture_output=True, text=True
)
if result.returncode != 0:
    fail(f"a manifest does not validate:\n{result.stdout}{result.stderr}")

job = next(
    d for d in yaml.safe_load_all(open(MANIFESTS[0])) if d and d.get("kind") == "Job"
)
spec = job["spec"]
pod = spec["template"]["spec"]["containers"][0]
k8s = flags(shlex.split(" ".join(pod["args"])))
script = open("studies/cluster/slurm-table-5-1.sh").read()
body = script[script.index("exec target/release/twin"):].replace("\\\n", " ")
slurm = flags(shlex.split(body.split("\n")[0]))
defaults = dict(re.findall(r"^(\w+)=\$\{\w+:-([^}]+)\}$", script, re.M))

names_k8s = [w for w in k8s if w.startswith("--")]
names_slurm = [w for w in slurm if w.startswith("--")]
if names_k8s != names_slurm:
    fail(f"flags differ: Kubernetes {names_k8s}, Slurm {names_slurm}")
if k8s[0] != "montecarlo" or slurm[0] != "montecarlo":
    fail(f"not the same subcommand: {k8s[0]} / {slurm[0]}")
if k8s[1] != defaults.get("STUDY"):
    fail(f"study {k8s[1]} against the Slurm default {defaults.get('STUDY')}")
shard_k8s = k8s[k8s.index("--shard") + 1]
shards = int(shard_k8s.split("/")[1])
if shards != int(defaults["SHARDS"]) or shards != spec["completions"] or spec["completionMode"] != "Indexed":
    fail(
        f"shards: Kubernetes {shard_k8s} over {spec['completions']} completions, "
        f"Slurm {defaults['SHARDS']}"
    )
print(
    f"check-k8s: both manifests validate; the pod runs `twin {' '.join(names_k8s)}` on "
    f"{k8s[1]} in {shards} indexed shards, as the Slurm task does"
)
