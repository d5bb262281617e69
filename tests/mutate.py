#!/usr/bin/env python3
"""tests/mutate.py: mutation testing (make mutate). Each mutation in
tests/mutations.txt is a small, realistic bug: one exact piece of source text
and its replacement. In a scratch copy of the source tree (built once), every
mutation in turn is applied, the programs its tests need are rebuilt, and
those tests run under the per-test time limit; the mutation is caught when a
test fails. The original text is then put back. Prints one line per mutation
and a summary; exits 1 when any mutation is missed, does not apply (its text
is not found exactly once: the list is stale) or does not build.

  tests/mutate.py [--srcdir DIR] [--keep] [--only ID[,ID...]] [--configure "FLAGS"]

The scratch copy lives in $TMPDIR; the working tree is never touched."""
import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time


def parse(path):
    """Blocks separated by blank lines; '#' comment lines; fields:
    id: NAME / file: PATH / tests: T1 T2 ... / why: TEXT / - OLD LINE(S) / + NEW LINE(S)"""
    muts, cur = [], None
    with open(path) as f:
        lines = f.read().split("\n")
    for ln in lines + [""]:
        if ln.startswith("#"):
            continue
        if not ln.strip():
            if cur:
                muts.append(cur)
            cur = None
            continue
        if cur is None:
            cur = {"old": [], "new": []}
        if ln.startswith("- ") or ln == "-":
            cur["old"].append(ln[2:])
        elif ln.startswith("+ ") or ln == "+":
            cur["new"].append(ln[2:])
        else:
            k, _, v = ln.partition(":")
            cur[k.strip()] = v.strip()
    for m in muts:
        for k in ("id", "file", "tests", "why"):
            if k not in m:
                sys.exit("mutations.txt: a block without '%s:' (%s)" % (k, m.get("id", "?")))
        if not m["old"]:
            sys.exit("mutations.txt: %s has no '- ' line" % m["id"])
        m["old"] = "\n".join(m["old"])
        m["new"] = "\n".join(m["new"])
    return muts


def run(cmd, cwd, log, timeout=None, env=None):
    with open(log, "a") as lf:
        lf.write("$ %s\n" % cmd)
        lf.flush()
        try:
            return subprocess.run(cmd, shell=True, cwd=cwd, stdout=lf, stderr=subprocess.STDOUT,
                                  timeout=timeout, env=env, start_new_session=True).returncode
        except subprocess.TimeoutExpired:
            lf.write("(timed out after %s s)\n" % timeout)
            return 124


def copy_tree(src, dst):
    """The tracked files of src into dst (times kept)."""
    files = subprocess.run(["git", "ls-files", "-z"], cwd=src, capture_output=True, check=True).stdout.decode()
    for f in files.split("\0"):
        if f and os.path.isfile(os.path.join(src, f)):
            os.makedirs(os.path.dirname(os.path.join(dst, f)) or dst, exist_ok=True)
            shutil.copy2(os.path.join(src, f), os.path.join(dst, f))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--srcdir", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
    ap.add_argument("--keep", action="store_true", help="keep the scratch tree")
    ap.add_argument("--only", default="", help="comma-separated mutation ids")
    ap.add_argument("--configure", default="--enable-werror --with-ceres --with-gl --with-openvdb")
    ap.add_argument("--test-timeout", default="240", help="per-test limit in seconds (NBT_TEST_TIMEOUT)")
    ap.add_argument("-j", default="2")
    a = ap.parse_args()
    src = os.path.abspath(a.srcdir)
    muts = parse(os.path.join(src, "tests", "mutations.txt"))
    if a.only:
        want = set(a.only.split(","))
        muts = [m for m in muts if m["id"] in want]
    ids = [m["id"] for m in muts]
    if len(set(ids)) != len(ids):
        sys.exit("mutations.txt: duplicate ids")

    # check every mutation applies before building anything
    stale = []
    for m in muts:
        text = open(os.path.join(src, m["file"])).read()
        if text.count(m["old"]) != 1:
            stale.append("%s: its text occurs %d times in %s" % (m["id"], text.count(m["old"]), m["file"]))
    for s in stale:
        print("STALE  " + s)
    if stale:
        return 1

    scratch = tempfile.mkdtemp(prefix="nbt-mutate.")
    log = os.path.join(scratch, "mutate.log")
    tree = os.path.join(scratch, "src")
    copy_tree(src, tree)
    j = "-j" + a.j
    print("mutate: %d mutations; scratch tree %s (log: mutate.log)" % (len(muts), tree), flush=True)
    t0 = time.time()
    if run("autoreconf -fi && ./configure -q %s && make %s && make %s check TESTS=" % (a.configure, j, j),
           tree, log) != 0:
        print("mutate: the unmutated tree does not build; see " + log)
        return 1
    print("mutate: baseline built in %.0f s" % (time.time() - t0), flush=True)
    env = dict(os.environ, NBT_TEST_TIMEOUT=a.test_timeout)
    caught = missed = broken = 0
    for m in muts:
        path = os.path.join(tree, m["file"])
        orig = open(path).read()
        tests = m["tests"].split()
        # the programs those tests run: test binaries themselves, the CLI programs for shell tests
        targets = [t for t in tests if not t.endswith(".sh")]
        if any(t.endswith(".sh") for t in tests):
            targets += ["nbt-gen", "nbt-fit", "nbt-scatter", "tests/mkexr"]
        t1 = time.time()
        with open(path, "w") as f:
            f.write(orig.replace(m["old"], m["new"]))
        try:
            rc = run("make %s %s" % (j, " ".join(targets)), tree, log)
            if rc != 0:
                status = "NOBUILD"
                broken += 1
            else:
                progs = " ".join(t for t in tests if not t.endswith(".sh"))
                rc = run("make %s check-TESTS TESTS='%s' check_PROGRAMS='%s'" % (j, " ".join(tests), progs),
                         tree, log, env=env)
                if rc != 0:
                    failed = []
                    for t in tests:
                        trs = os.path.join(tree, (t[:-3] if t.endswith(".sh") else t) + ".trs")
                        if os.path.exists(trs) and ":test-result: PASS" not in open(trs).read():
                            failed.append(os.path.basename(t))
                    status = "caught by " + ",".join(failed or ["make"])
                    caught += 1
                else:
                    status = "MISSED"
                    missed += 1
        finally:
            with open(path, "w") as f:
                f.write(orig)
            os.utime(path, None)  # newer than the mutated objects: the next build rebuilds it
        print("%-22s %-26s %4.0f s  %s" % (m["id"], m["file"], time.time() - t1, status), flush=True)
        if status in ("MISSED", "NOBUILD"):
            print("    (%s)" % m["why"], flush=True)
    print("mutate: %d mutations, %d caught, %d missed, %d did not build (%.0f s)" %
          (len(muts), caught, missed, broken, time.time() - t0))
    if a.keep:
        print("mutate: kept " + scratch)
    else:
        shutil.rmtree(scratch, ignore_errors=True)
    return 0 if missed == 0 and broken == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
