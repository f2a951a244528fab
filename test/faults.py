#!/usr/bin/env python3
"""Faults around virtual-unwrap: the process killed while it writes, a full disk and an
address-space limit. Each must end in a clear one-line error (or, for a kill, a dead
process) and never in partial output: the output folder either does not exist or holds a
complete result.

Usage: faults.py TOOL WORK_DIR kill|disk|memory
Exit 0: passed; 77: skipped (the machine does not allow the fault, e.g. no tmpfs mount);
1: failed. Needs only the Python standard library."""

import json
import os
import random
import resource
import shutil
import signal
import subprocess
import sys
import time

SKIP = 77


def run(tool, arguments, limit=None, **kwargs):
    preexec = None
    if limit is not None:
        def preexec():
            resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
    return subprocess.run([tool] + arguments, capture_output=True, text=True, timeout=600,
                          preexec_fn=preexec, **kwargs)


def one_error_line(result, pattern_words):
    """The last line of standard error is the only error line and names the problem."""
    lines = [l for l in result.stderr.splitlines() if l.strip()]
    errors = [l for l in lines if l.startswith("virtual-unwrap: error: ")]
    if result.returncode <= 0:
        return "exit status %d (a signal or success)" % result.returncode
    if len(errors) != 1 or lines[-1] != errors[0]:
        return "not one error line: %r" % result.stderr[-400:]
    if not all(word in errors[0] for word in pattern_words):
        return "message %r does not name %s" % (errors[0], pattern_words)
    return None


def leftovers(folder, name):
    """Entries of folder that belong to the output `name`: itself or its staging folders."""
    return sorted(e for e in os.listdir(folder) if e == name or e.startswith("." + name + ".partial-")
                  or e.startswith(name + ".partial"))


def complete_unwrap(folder):
    expected = ["texture.png", "texture.tif", "mask.png", "layers.tif", "surface.obj", "surface.vtp",
                "flat.obj", "preview.png", "report.json"]
    missing = [f for f in expected if not os.path.isfile(os.path.join(folder, f))]
    if missing:
        return "incomplete output, missing %s" % missing
    with open(os.path.join(folder, "report.json")) as f:
        json.load(f)
    return None


def unwrap_completes(tool, volume, out, what):
    """Runs unwrap to `out`; returns the problem ("WHAT failed: ..." or an incomplete
    output), or None when the whole result is there."""
    result = run(tool, ["unwrap", volume, "-o", out, "-q"])
    if result.returncode != 0:
        return "%s failed: %s" % (what, result.stderr)
    return complete_unwrap(out)


def unwrap_killed(tool, volume, work, sig, stage, delay):
    """Runs unwrap and sends sig `delay` seconds after the stage starts; returns the
    process's exit status."""
    process = subprocess.Popen([tool, "unwrap", volume, "-o", os.path.join(work, "out"), "--json"],
                               stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    for line in process.stderr:
        try:
            event = json.loads(line)
        except ValueError:
            continue
        if event.get("event") == "start" and event.get("stage") == stage:
            time.sleep(delay)
            process.send_signal(sig)
            break
    process.stderr.read()
    return process.wait()


def kill_test(tool, work):
    failures = []
    phantom = os.path.join(work, "phantom")
    result = run(tool, ["phantom", "standard", "-o", phantom])
    if result.returncode != 0:
        return ["phantom failed: " + result.stderr]
    volume = os.path.join(phantom, "volume")
    rng = random.Random()
    seed = rng.randrange(1 << 30)
    rng.seed(seed)
    print("delays drawn with seed %d" % seed)
    # Killed outright while writing, at several moments of the write stage: the output
    # folder never appears; the hidden staging folder of the dead process stays.
    for attempt in range(4):
        delay = rng.uniform(0.0, 0.25)
        status = unwrap_killed(tool, volume, work, signal.SIGKILL, "write", delay)
        left = leftovers(work, "out")
        if status == 0:
            print("SIGKILL %.3f s into writing: finished before the signal" % delay)
            if complete_unwrap(os.path.join(work, "out")):
                failures.append("finished, but " + complete_unwrap(os.path.join(work, "out")))
            shutil.rmtree(os.path.join(work, "out"))
            continue
        print("SIGKILL %.3f s into writing: status %d, left %s" % (delay, status, left))
        if "out" in left:
            # Killed after the result was moved into place (while the process ended):
            # complete, or a failure.
            problem = complete_unwrap(os.path.join(work, "out"))
            if problem:
                failures.append("SIGKILL while writing left a partial output folder: " + problem)
            shutil.rmtree(os.path.join(work, "out"))
    # Interrupted or terminated while writing or earlier: nothing at all remains (the
    # stale staging folders of the killed runs are removed by the next run too).
    for sig, stage in ((signal.SIGTERM, "write"), (signal.SIGINT, "write"), (signal.SIGTERM, "texture"),
                       (signal.SIGHUP, "flatten")):
        delay = rng.uniform(0.0, 0.1)
        status = unwrap_killed(tool, volume, work, sig, stage, delay)
        left = leftovers(work, "out")
        print("%s %.3f s into %s: status %d, left %s" % (sig.name, delay, stage, status, left))
        if status == 0:
            shutil.rmtree(os.path.join(work, "out"), ignore_errors=True)
            continue
        if status != -sig:
            failures.append("%s: status %d, not ended by the signal" % (sig.name, status))
        if "out" in left and not complete_unwrap(os.path.join(work, "out")):
            shutil.rmtree(os.path.join(work, "out"))  # the result was complete before the signal
            left.remove("out")
        if left:
            failures.append("%s during %s left %s" % (sig.name, stage, left))
    # The next complete run: the whole result, nothing stale beside it.
    problem = unwrap_completes(tool, volume, os.path.join(work, "out"), "unwrap after the kills")
    if problem:
        failures.append(problem)
    elif leftovers(work, "out") != ["out"]:
        failures.append("stale staging folders remain: %s" % leftovers(work, "out"))
    # The phantom writer, terminated while it writes its series.
    process = subprocess.Popen([tool, "phantom", "standard", "-o", os.path.join(work, "ph2")],
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    for _ in range(2000):
        staging = [e for e in os.listdir(work) if e.startswith(".ph2.partial-")]
        if staging and os.path.isdir(os.path.join(work, staging[0], "volume")):
            break
        time.sleep(0.005)
    process.send_signal(signal.SIGTERM)
    status = process.wait()
    left = leftovers(work, "ph2")
    print("phantom SIGTERM while writing: status %d, left %s" % (status, left))
    if status != 0 and left:
        failures.append("phantom terminated while writing left %s" % left)
    return failures


def disk_test(tool, work):
    mount = os.path.join(work, "small_disk")
    os.makedirs(mount, exist_ok=True)
    # 2 MiB: less than any result below needs (the unwrap result is about 9 MiB).
    if subprocess.run(["mount", "-t", "tmpfs", "-o", "size=2m", "tmpfs", mount],
                      capture_output=True).returncode != 0:
        print("SKIP: cannot mount a small tmpfs here (needs root and mount rights)")
        return None
    failures = []
    try:
        phantom = os.path.join(work, "phantom")
        result = run(tool, ["phantom", "standard", "-o", phantom])
        if result.returncode != 0:
            return ["phantom failed: " + result.stderr]
        volume = os.path.join(phantom, "volume")
        cases = [
            ("unwrap", ["unwrap", volume, "-o", os.path.join(mount, "out"), "-q"], "out"),
            ("segment", ["segment", os.path.join(work, "volume.mha"), "-o", os.path.join(mount, "seg")], "seg"),
            ("phantom", ["phantom", "standard", "-o", os.path.join(mount, "ph")], "ph"),
        ]
        # segment reads a single file: the phantom as MetaImage.
        result = run(tool, ["phantom", "standard", "-o", os.path.join(work, "ph_mha"), "--format", "mha"])
        if result.returncode != 0:
            return ["phantom --format mha failed: " + result.stderr]
        shutil.copy(os.path.join(work, "ph_mha", "volume.mha"), os.path.join(work, "volume.mha"))
        for name, arguments, output in cases:
            result = run(tool, arguments)
            problem = one_error_line(result, ["not enough disk space", "need", "free"])
            left = leftovers(mount, output)
            print("%-8s on a full disk: status %d, %s, left %s" % (name, result.returncode,
                                                                   (result.stderr.strip().splitlines() or [""])[-1],
                                                                   left))
            if problem:
                failures.append("%s: %s" % (name, problem))
            if left:
                failures.append("%s left %s on the full disk" % (name, left))
        # The same unwrap with room enough completes: the check asks for what is needed.
        subprocess.run(["umount", mount], check=True)
        subprocess.run(["mount", "-t", "tmpfs", "-o", "size=48m", "tmpfs", mount], check=True)
        problem = unwrap_completes(tool, volume, os.path.join(mount, "out"), "unwrap with 48 MiB free")
        if problem:
            failures.append(problem)
        else:
            print("unwrap with 48 MiB free: complete")
    finally:
        subprocess.run(["umount", mount])
    return failures


def memory_test(tool, work):
    failures = []
    # A volume of 1024^3 16-bit voxels (2 GiB of data) in a sparse file, under a 4 GiB
    # address-space limit: refused before reading, naming the need and the limit.
    raw = os.path.join(work, "big.raw")
    with open(raw, "wb") as f:
        f.truncate(1024 * 1024 * 1024 * 2)
    header = os.path.join(work, "big.mha")
    with open(header, "w") as f:
        f.write("ObjectType = Image\nNDims = 3\nBinaryData = True\nBinaryDataByteOrderMSB = False\n"
                "DimSize = 1024 1024 1024\nElementSpacing = 0.1 0.1 0.1\nElementType = MET_SHORT\n"
                "ElementDataFile = big.raw\n")
    limit = 4 << 30
    result = run(tool, ["unwrap", header, "-o", os.path.join(work, "out"), "-q"], limit=limit)
    problem = one_error_line(result, ["needs about", "memory", "ulimit -v", "4.00 GiB"])
    print("unwrap 1024^3 voxels under ulimit -v 4 GiB: status %d, %s" %
          (result.returncode, (result.stderr.strip().splitlines() or [""])[-1]))
    if problem:
        failures.append("unwrap: " + problem)
    if leftovers(work, "out"):
        failures.append("unwrap left %s" % leftovers(work, "out"))
    # An allocation that fails where no estimate was made: the phantom writer asked for a
    # volume larger than the limit allows.
    result = run(tool, ["phantom", "standard", "-o", os.path.join(work, "ph"), "--voxel-size", "0.01"],
                 limit=2 << 30)
    problem = one_error_line(result, ["memory", "ulimit -v"])
    print("phantom at 0.01 mm under ulimit -v 2 GiB: status %d, %s" %
          (result.returncode, (result.stderr.strip().splitlines() or [""])[-1]))
    if problem:
        failures.append("phantom: " + problem)
    if leftovers(work, "ph"):
        failures.append("phantom left %s" % leftovers(work, "ph"))
    return failures


def main():
    tool, work, case = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2]), sys.argv[3]
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    failures = {"kill": kill_test, "disk": disk_test, "memory": memory_test}[case](tool, work)
    if failures is None:
        return SKIP
    for f in failures:
        print("FAILED: " + f)
    print("%s: %d failure(s)" % (case, len(failures)))
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
