#!/usr/bin/env python3
"""tests/mutate_sample.py: random mutation testing (make mutate-sample N= SEED=).

Unlike tests/mutations.txt, whose bugs were chosen by hand, the mutants here are
drawn by a program: every C, C++ and GLSL source of libnbt, the shaders,
scatter/, gen/ and fit/ is scanned for mutation sites of these kinds

  aor    a binary + - * / replaced by its inverse (+ <-> -, * <-> /)
  ror    a comparison changed: < <= > >= == != (off-by-one in bounds, flips)
  lcr    && <-> ||
  crp    a constant changed: an integer n -> n + 1 and n - 1, a real x -> 1.1 x
  idx    an index off by one: a[i] -> a[i + 1] and a[i - 1]
  neg    a unary minus dropped
  drop   a term dropped: a + b -> a, a - b -> a
  swap   the first two arguments of a call swapped

and SEED orders all (site, replacement) pairs at random. Mutants are taken in
that order until N of them compile; those that do not compile are counted and
skipped (they are not bugs a test could miss).

Each mutant is applied in a scratch copy of the tree, rebuilt with make, and
run against the tests that execute its line: a per-test line-coverage map
(gcov) is made once per source revision from a --coverage build, so a test
that never executes the mutated line is not run (it cannot see the mutant: the
programs are deterministic). A line gcov does not know (a declaration, a
macro, a constant table) runs every test that executes any line of its file;
a GLSL line runs every test that executes libnbt-gl. A line no test executes
runs the tests that use `ulimit -f 0` (gcov records nothing under it). --full N runs the first
N mutants against the whole suite as well and reports whether the two
verdicts agree (the check that the subset equals the whole suite).

The scratch tree is built with -Werror, as CI builds: a mutant the compiler
warns about does not compile and is counted with those skipped. A header
whose lines no test executes (macros only) runs the tests of the files that
include it.

A mutant is killed when one of its tests fails or runs past SLOW (default 3)
times its unmutated time (at least 20 SLOW s). Survivors are listed with their diff; each is
classified by hand in doc/mutation.md (equivalent, or a real bug and the test
written for it).

  tests/mutate_sample.py [--n 150] [--seed S] [--srcdir DIR] [--work DIR]
                         [--full K] [--sites] [--reverse] [--skip K] [--slow 3] [-j 2]

--sites prints the site counts per file and kind and exits. --skip K resumes a
stopped runner (same --seed, --reverse and source): its first K mutants, built
or not, are passed over and the numbering goes on from K. --work keeps the
scratch builds and the coverage map between runs (default: a temporary
directory, removed at the end). Results go to stdout, one line per mutant."""
import argparse
import concurrent.futures
import glob
import json
import os
import random
import re
import shutil
import subprocess
import sys
import tempfile
import time

from mutate import copy_tree, run  # tests/mutate.py: the hand-picked list's driver

SOURCES = ["libnbt/*.c", "libnbt/*.h", "libnbt/nbt/*.h", "shaders/*.c", "shaders/*.h", "shaders/*.glsl",
           "scatter/*.c", "scatter/*.h", "gen/*.c", "gen/*.h", "fit/*.c", "fit/*.cc", "fit/*.h"]
# generated data (written by doc/*.sh from counted photons) and a bitmap font: numbers, not code
EXCLUDE = {"libnbt/screen_model_hg.h", "libnbt/beam_fit_data.h", "gen/font5x7.h"}

TOKEN = re.compile(r"""
    (?P<num>(?:\d+\.\d*|\.\d+|\d+)(?:[eE][+-]?\d+)?[fFuUlL]*|0[xX][0-9a-fA-F]+[uUlL]*)
  | (?P<id>[A-Za-z_]\w*)
  | (?P<op><<=|>>=|->|\+\+|--|&&|\|\||<=|>=|==|!=|<<|>>|[-+*/%<>=!&|^~?:;,.()\[\]{}])
  | (?P<ws>\s+)
""", re.X)
QUALIFIERS = {"static", "const", "extern", "inline", "unsigned", "signed", "struct", "uniform", "in", "out",
              "inout", "highp", "mediump", "lowp", "flat"}
KEYWORDS = {"return", "case", "sizeof", "if", "while", "for", "switch", "else", "do", "goto"}
OPERAND_END = {"num", "id", ")", "]"}


def code_mask(text):
    """The text with comments, string and character literals and preprocessor
    lines other than #define blanked out (same length, newlines kept)."""
    out, i, n = list(text), 0, len(text)
    line_start = True
    while i < n:
        c = text[i]
        if line_start and c in " \t":
            i += 1
            continue
        if line_start and c == "#":
            j = text.find("\n", i)
            j = n if j < 0 else j
            while j > 0 and text[j - 1] == "\\" and j < n:  # continued lines
                j2 = text.find("\n", j + 1)
                j = n if j2 < 0 else j2
            if not re.match(r"#\s*define\s+\w+\s+[-+(0-9.]", text[i:j]):
                for k in range(i, j):
                    if out[k] != "\n":
                        out[k] = " "
            else:  # keep the value of a numeric #define, blank the name part
                m = re.match(r"#\s*define\s+\w+", text[i:j])
                for k in range(i, i + m.end()):
                    out[k] = " "
            i = j
            continue
        line_start = False
        if c == "\n":
            line_start = True
            i += 1
        elif text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            for k in range(i, j):
                out[k] = " "
            i = j
        elif text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            for k in range(i, j):
                if out[k] != "\n":
                    out[k] = " "
            i = j
        elif c in "\"'":
            j = i + 1
            while j < n and text[j] != c:
                j += 2 if text[j] == "\\" else 1
            for k in range(i, min(j + 1, n)):
                if out[k] != "\n":
                    out[k] = " "
            i = j + 1
        else:
            i += 1
    return "".join(out)


def tokens(line):
    toks = []
    for m in TOKEN.finditer(line):
        kind = m.lastgroup
        if kind == "ws":
            continue
        v = m.group()
        toks.append((kind if kind in ("num", "id") else v, v, m.start(), m.end()))
    return toks


def fmt_real(x):
    s = repr(x)
    return s if ("." in s or "e" in s or "inf" in s or "nan" in s) else s + ".0"


def match_close(toks, i, op="(", cl=")"):
    depth = 0
    for j in range(i, len(toks)):
        if toks[j][0] == op:
            depth += 1
        elif toks[j][0] == cl:
            depth -= 1
            if depth == 0:
                return j
    return -1


def line_sites(line, glsl):
    """(kind, col_start, col_end, replacement) for one line of code."""
    toks = tokens(line)
    sites = []
    if "__attribute__" in line:
        return sites
    # a declaration starts "type name" or "type *name" (qualifiers first)
    ids = [t for t in toks if t[0] != "*"][:4]
    while ids and ids[0][1] in QUALIFIERS:
        ids.pop(0)
    decl = len(ids) >= 2 and ids[0][0] == "id" and ids[1][0] == "id" and ids[0][1] not in KEYWORDS
    for i, (k, v, a, b) in enumerate(toks):
        prev = toks[i - 1][0] if i else None
        prevv = toks[i - 1][1] if i else None
        binary = prev in OPERAND_END and prevv not in KEYWORDS
        nxt = toks[i + 1] if i + 1 < len(toks) else None
        if k in ("+", "-", "*", "/") and binary:
            if k == "*" and prev == "id" and (decl and "=" not in [t[0] for t in toks[:i]] or
                                              (i + 2 < len(toks) and toks[i + 2][0] in ("=", ",", ";", ")", "[")
                                               and (i < 2 or toks[i - 2][0] in (";", "{", "(", ",")))):
                continue  # "type *name": a declaration, not a product
            inv = {"+": "-", "-": "+", "*": "/", "/": "*"}[k]
            sites.append(("aor", a, b, inv))
            # a term dropped: "+ x" where x is one operand ending the term
            if k in ("+", "-") and nxt and nxt[0] in ("id", "num") and i + 2 < len(toks) and \
                    toks[i + 2][0] in (")", ";", ",", "]", "+", "-", "<", ">", "<=", ">=", "==", "!=", "?", ":"):
                sites.append(("drop", a, nxt[3], ""))
        elif k in ("<", "<=", ">", ">=", "==", "!=") and binary:
            alts = {"<": ["<=", ">"], "<=": ["<", ">="], ">": [">=", "<"], ">=": [">", "<="],
                    "==": ["!="], "!=": ["=="]}[k]
            if k in ("<", ">") and glsl is False and line.lstrip().startswith("#"):
                continue
            for r in alts:
                sites.append(("ror", a, b, r))
        elif k in ("&&", "||"):
            sites.append(("lcr", a, b, "||" if k == "&&" else "&&"))
        elif k == "-" and not binary and nxt and nxt[0] in ("id", "num", "("):
            sites.append(("neg", a, b, ""))
        elif k == "num":
            if decl and prev == "[" and i >= 2 and toks[i - 2][0] == "id" and \
                    (i < 3 or toks[i - 3][0] in ("id", "*", ",")):
                continue  # an array's size in its declaration
            s = v.rstrip("fFuUlL")
            suf = v[len(s):]
            if s.lower().startswith("0x"):
                continue
            if re.fullmatch(r"\d+", s):
                n = int(s)
                sites.append(("crp", a, b, str(n + 1) + suf))
                if n > 0:
                    sites.append(("crp", a, b, str(n - 1) + suf))
            else:
                x = float(s)
                sites.append(("crp", a, b, (fmt_real(x * 1.1) if x != 0 else "1.0") + suf))
        elif k == "[" and prev in ("id", "]", ")") and not \
                (decl and prev == "id" and i >= 2 and toks[i - 2][0] in ("id", "*", ",")):
            j = match_close(toks, i, "[", "]")
            if j > i + 1:
                inner = line[toks[i + 1][2]:toks[j - 1][3]]
                for d in (" + 1", " - 1"):
                    sites.append(("idx", toks[i + 1][2], toks[j - 1][3], "(" + inner + ")" + d))
        elif k == "(" and prev == "id" and prevv not in KEYWORDS and not (decl and i == 2):
            j = match_close(toks, i)
            if j < 0:
                continue
            # top-level commas
            depth, commas = 0, []
            for t in range(i + 1, j):
                if toks[t][0] in ("(", "["):
                    depth += 1
                elif toks[t][0] in (")", "]"):
                    depth -= 1
                elif toks[t][0] == "," and depth == 0:
                    commas.append(t)
            if commas and j > commas[0] + 1 and commas[0] > i + 1:
                end2 = commas[1] if len(commas) > 1 else j
                a1 = line[toks[i + 1][2]:toks[commas[0] - 1][3]]
                a2 = line[toks[commas[0] + 1][2]:toks[end2 - 1][3]]
                if a1.strip() != a2.strip():
                    sites.append(("swap", toks[i + 1][2], toks[end2 - 1][3], a2 + ", " + a1))
    return sites


def enumerate_sites(src):
    files = []
    for pat in SOURCES:
        files += sorted(glob.glob(os.path.join(src, pat)))
    tracked = set(subprocess.run(["git", "ls-files"], cwd=src, capture_output=True, text=True).stdout.split())
    out = []
    for path in files:
        rel = os.path.relpath(path, src)
        if rel in EXCLUDE or rel not in tracked:
            continue
        text = open(path).read()
        masked = code_mask(text)
        glsl = rel.endswith(".glsl")
        for ln, (orig, code) in enumerate(zip(text.split("\n"), masked.split("\n")), 1):
            for kind, a, b, rep in line_sites(code, glsl):
                new = orig[:a] + rep + orig[b:]
                if new != orig:
                    out.append({"file": rel, "line": ln, "kind": kind, "old": orig, "new": new})
    return out


def make_var(tree, expr):
    out = subprocess.run(["make", "-s", "--eval=print-var: ; @echo %s" % expr, "print-var"], cwd=tree,
                         capture_output=True, text=True)
    return out.stdout.split()


def test_list(tree, log):
    return make_var(tree, "$(TESTS)")


def rebuild(tree, f, jobs, log, programs):
    """Rebuilds what file f goes into. A library's programs are not relinked:
    libtool's wrappers load the rebuilt shared library (their timestamps are
    refreshed so that make does not relink them either)."""
    if f.startswith("libnbt/") and f.endswith(".c"):
        cmd = "make -j%s libnbt/libnbt.la" % jobs
    elif f.startswith("shaders/") and f != "shaders/nbt_shader_variants.c" and not f.endswith(".h"):
        cmd = "make -j%s shaders/libnbt-gl.la" % jobs
        # the HLSL/MSL that test_shaders_cross.sh reads are made from the GLSL
        # by nbt-shader-variants: regenerate them where the tree builds them
        # (a failure is left for that test to judge, not taken as no build)
        if f.endswith(".glsl") and re.search(r"(?m)^shaders/cross\.stamp:", open(os.path.join(tree, "Makefile")).read()):
            cmd += " && { make shaders/nbt-shader-variants shaders/cross.stamp || true; }"
    else:
        cmd = "make -j%s && make -j%s check TESTS=" % (jobs, jobs)
    rc = run(cmd, tree, log)
    now = time.time()
    for p in programs:
        path = os.path.join(tree, p)
        if os.path.exists(path):
            os.utime(path, (now, now))
    return rc


def run_one_test(tree, t, timeout, tag):
    """Runs one test through automake's harness; returns (verdict, seconds):
    PASS, SKIP, FAIL or TIMEOUT."""
    t0 = time.time()
    base = t[:-3] if t.endswith(".sh") else t
    logname = "mutlog-%s-%s.log" % (tag, os.path.basename(base))
    # the suite's own per-test limit (tests/timelimit.sh, 300 s) must not decide first: under
    # --coverage and load test_gl took longer and its map came back empty (a FAIL, no lines)
    cmd = "NBT_TEST_TIMEOUT=%d make check-TESTS TESTS='%s' check_PROGRAMS= TEST_SUITE_LOG=%s" % (
        int(timeout) + 60, t, logname)
    with open(os.path.join(tree, logname + ".out"), "w") as lf:
        try:
            p = subprocess.Popen(cmd, shell=True, cwd=tree, stdout=lf, stderr=subprocess.STDOUT,
                                 start_new_session=True)
            p.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            os.killpg(p.pid, 9)
            p.wait()
            return "TIMEOUT", time.time() - t0
    trs = os.path.join(tree, base + ".trs")
    res = open(trs).read() if os.path.exists(trs) else ""
    if ":test-result: PASS" in res:
        v = "PASS"
    elif ":test-result: SKIP" in res:
        v = "SKIP"
    else:
        v = "FAIL"
    return v, time.time() - t0


def find_files(top, suffix):
    """Files ending in suffix under top, hidden directories (libtool's .libs) included."""
    return [os.path.join(d, f) for d, _, fs in os.walk(top) for f in fs if f.endswith(suffix)]


def gcov_lines(tree):
    """{file: set(lines executed)} from the .gcda files under tree."""
    cov = {}
    gcdas = [os.path.relpath(p, tree) for p in find_files(tree, ".gcda")]
    for g in gcdas:
        d = os.path.dirname(g) or "."
        r = subprocess.run(["gcov", "-t", "-j", os.path.basename(g)], cwd=os.path.join(tree, d),
                           capture_output=True, text=True)
        for doc in r.stdout.splitlines():
            doc = doc.strip()
            if not doc.startswith("{"):
                continue
            data = json.loads(doc)
            cwd = data.get("current_working_directory", os.path.join(tree, d))
            for f in data.get("files", []):
                name = os.path.relpath(os.path.realpath(os.path.join(cwd, f["file"])), os.path.realpath(tree))
                s = cov.setdefault(name, set())
                for ln in f.get("lines", []):
                    if ln["count"] > 0:
                        s.add(ln["line_number"])
                cov.setdefault(name + "#known", set()).update(ln["line_number"] for ln in f.get("lines", []))
    return cov


def coverage_map(src, work, log, jobs):
    """Per test: lines executed and its time; cached in WORK by the tree's content hash."""
    h = subprocess.run("git ls-files -s | sha1sum", shell=True, cwd=src, capture_output=True,
                       text=True).stdout.split()[0]
    cache = os.path.join(work, "coverage-%s.json" % h[:12])
    if os.path.exists(cache):
        return json.load(open(cache))
    tree = os.path.join(work, "cov")
    print("mutate-sample: coverage build in %s" % tree, flush=True)
    flags = "-O1 -g --coverage"
    if os.path.exists(os.path.join(tree, "config.status")):  # a kept build: bring it to the source revision
        copy_tree(src, tree)
        if run("make -j%s && make -j%s check TESTS=" % (jobs, jobs), tree, log) != 0:
            sys.exit("mutate-sample: the coverage build failed; see " + log)
    else:
        shutil.rmtree(tree, ignore_errors=True)
        copy_tree(src, tree)
        if run("autoreconf -fi && ./configure -q --disable-static --with-ceres --with-gl --with-openvdb "
               "--with-mpi CFLAGS='%s' CXXFLAGS='%s' LDFLAGS=--coverage && make -j%s && make -j%s check TESTS=" %
               (flags, flags, jobs, jobs), tree, log) != 0:
            sys.exit("mutate-sample: the coverage build failed; see " + log)
    tests = test_list(tree, log)
    result = {"tests": {}}
    for t in tests:
        for g in find_files(tree, ".gcda"):
            os.unlink(g)
        v, secs = run_one_test(tree, t, 1800, "cov")
        cov = gcov_lines(tree)
        result["tests"][t] = {"verdict": v, "seconds": secs,
                              "lines": {f: sorted(s) for f, s in cov.items() if not f.endswith("#known")},
                              "known": {f[:-6]: sorted(s) for f, s in cov.items() if f.endswith("#known")}}
        print("mutate-sample: coverage of %-34s %-4s %6.1f s, %d files" %
              (t, v, secs, len([f for f in cov if not f.endswith("#known")])), flush=True)
    json.dump(result, open(cache, "w"))
    return result


def includers(src, header):
    """The sources that include header (by its base name), through other headers too."""
    found, todo = set(), [os.path.basename(header)]
    files = [f for pat in SOURCES for f in glob.glob(os.path.join(src, pat))]
    while todo:
        name = todo.pop()
        inc = re.compile(r'^\s*#\s*include\s*[<"](?:[\w/]*/)?%s[>"]' % re.escape(name), re.M)
        for path in files:
            rel = os.path.relpath(path, src)
            if rel not in found and inc.search(open(path, errors="replace").read()):
                found.add(rel)
                if rel.endswith(".h"):
                    todo.append(os.path.basename(rel))
    return found


# tests that read the GLSL without running libnbt-gl (gcov cannot see them)
GLSL_TESTS = {"tests/test_shaders_cross.sh"}


def unmeasured_tests(src, cov):
    """The tests whose programs run under `ulimit -f 0` at some point: gcov
    cannot write its data there, so the map may miss lines they execute."""
    return sorted(t for t, d in cov["tests"].items() if d["verdict"] != "SKIP" and t.endswith(".sh") and
                  "ulimit -f" in open(os.path.join(src, t), errors="replace").read())


def tests_for(m, cov, src):
    """The tests that can see mutant m: those executing its line; where gcov
    does not know the line, those executing any line of the file; for a
    header no test executes a line of (macros only), those executing any
    line of a file that includes it; for GLSL, those running libnbt-gl and
    the HLSL/MSL cross-compile check."""
    f, ln = m["file"], m["line"]
    out = []
    known = any(ln in set(d["known"].get(f, [])) for d in cov["tests"].values())
    files = {f}
    if f.endswith(".h") and not any(d["lines"].get(f) for d in cov["tests"].values()):
        files |= includers(src, f)
    for t, d in cov["tests"].items():
        if d["verdict"] == "SKIP":
            continue
        if f.endswith(".glsl"):  # run through libnbt-gl, or cross-compiled to HLSL/MSL (no C line executes)
            hit = t in GLSL_TESTS or any(k.startswith("shaders/nbt_gl") and v for k, v in d["lines"].items())
        elif known:
            hit = ln in set(d["lines"].get(f, []))
        else:
            hit = any(d["lines"].get(g) for g in files)
        if hit:
            out.append(t)
    return sorted(out, key=lambda t: cov["tests"][t]["seconds"])


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--srcdir", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))
    ap.add_argument("--n", type=int, default=150)
    ap.add_argument("--seed", default="", help="an integer; empty: the clock")
    ap.add_argument("--work", default="")
    ap.add_argument("--full", type=int, default=0)
    ap.add_argument("--sites", action="store_true")
    ap.add_argument("--reverse", action="store_true",
                    help="take the permutation from its end (a second runner on another --work: disjoint mutants)")
    ap.add_argument("--skip", type=int, default=0,
                    help="pass over the first K mutants of this runner's order (those already run: the built ones "
                         "plus those that did not compile, as the summary counts them), to resume a stopped run")
    ap.add_argument("-j", default="2")
    ap.add_argument("--slow", type=float, default=3.0,
                    help="a test running past SLOW times its unmutated time (at least 20 SLOW s) kills the mutant")
    a = ap.parse_args()
    src = os.path.abspath(a.srcdir)
    sites = enumerate_sites(src)
    if a.sites:
        per = {}
        for s in sites:
            per.setdefault(s["file"], {}).setdefault(s["kind"], 0)
            per[s["file"]][s["kind"]] += 1
        for f in sorted(per):
            print("%-34s %6d  %s" % (f, sum(per[f].values()),
                                     " ".join("%s %d" % kv for kv in sorted(per[f].items()))))
        print("%d sites in %d files" % (len(sites), len(per)))
        return 0
    seed = int(a.seed) if a.seed else int(time.time())
    order = list(range(len(sites)))
    random.Random(seed).shuffle(order)
    if a.reverse:
        order.reverse()
    work = os.path.abspath(a.work) if a.work else tempfile.mkdtemp(prefix="nbt-mutate-sample.")
    os.makedirs(work, exist_ok=True)
    log = os.path.join(work, "mutate-sample.log")
    print("mutate-sample: seed %d, %d candidate mutants in the tree, drawing until %d build; work %s" %
          (seed, len(sites), a.n, work), flush=True)
    cov = coverage_map(src, work, log, a.j)
    tree = os.path.join(work, "run")
    if not os.path.exists(os.path.join(tree, "config.status")):
        shutil.rmtree(tree, ignore_errors=True)
        copy_tree(src, tree)
        if run("autoreconf -fi && ./configure -q --disable-static --enable-werror --with-ceres --with-gl"
               " --with-openvdb --with-mpi && make -j%s && make -j%s check TESTS=" % (a.j, a.j), tree, log) != 0:
            sys.exit("mutate-sample: the unmutated tree does not build; see " + log)
    else:  # a kept tree: bring it to the source revision
        copy_tree(src, tree)
        run("make -j%s && make -j%s check TESTS=" % (a.j, a.j), tree, log)
    programs = make_var(tree, "$(PROGRAMS) $(check_PROGRAMS)")
    counts = {"killed": 0, "survived": 0, "nobuild": 0, "nocover": 0}
    survivors, agree, disagree = [], 0, 0
    t0 = time.time()
    done, skipped = 0, 0
    for idx in order:
        if done >= a.n:
            break
        m = sites[idx]
        path = os.path.join(tree, m["file"])
        orig = open(path).read()
        lines = orig.split("\n")
        if lines[m["line"] - 1] != m["old"]:
            continue
        if skipped < a.skip:  # run before (built or not): numbered on from there
            skipped += 1
            continue
        lines[m["line"] - 1] = m["new"]
        t1 = time.time()
        with open(path, "w") as f:
            f.write("\n".join(lines))
        try:
            if rebuild(tree, m["file"], a.j, log, programs) != 0:
                counts["nobuild"] += 1
                print("  - nobuild  %-26s %5d %-5s (does not compile; counted by --skip)" %
                      (m["file"], m["line"], m["kind"]), flush=True)
                continue
            done += 1
            tests = tests_for(m, cov, src)
            verdict, by = "survived", ""
            jobs = int(a.j)
            with concurrent.futures.ThreadPoolExecutor(max_workers=jobs) as ex:
                futs = {}
                pending = list(tests)
                while pending or futs:
                    while pending and len(futs) < jobs:
                        t = pending.pop(0)
                        lim = max(20.0 * a.slow, a.slow * cov["tests"][t]["seconds"])
                        futs[ex.submit(run_one_test, tree, t, lim, "m")] = t
                    fin, _ = concurrent.futures.wait(list(futs), return_when=concurrent.futures.FIRST_COMPLETED)
                    for fu in fin:
                        t = futs.pop(fu)
                        v, _ = fu.result()
                        if v in ("FAIL", "TIMEOUT") and verdict == "survived":
                            verdict, by = "killed", "%s (%s)" % (os.path.basename(t), v.lower())
                            pending = []
                    if verdict == "killed" and futs:
                        for fu in futs:  # let the running ones finish: their trs files must not be half-written
                            fu.result()
                        futs = {}
            if not tests:
                # gcov records nothing from programs run under `ulimit -f 0` (their
                # write-failure checks): run those tests before calling the line unrun
                blind = [t for t in unmeasured_tests(src, cov) if run_one_test(tree, t, max(
                    20.0 * a.slow, a.slow * cov["tests"][t]["seconds"]), "m")[0] in ("FAIL", "TIMEOUT")]
                if blind:
                    verdict, by = "killed", "%s (fail; no coverage recorded under ulimit -f)" % \
                        os.path.basename(blind[0])
                else:
                    counts["nocover"] += 1
                    verdict, by = "survived", "no test executes this line"
            full = ""
            if done <= a.full:
                allt = [t for t, d in cov["tests"].items() if d["verdict"] != "SKIP"]
                r = run("make -j%s check TESTS='%s' check_PROGRAMS=" % (a.j, " ".join(allt)), tree, log,
                        timeout=3600)
                fv = "killed" if r != 0 else "survived"
                full = " [whole suite: %s]" % fv
                if fv == verdict:
                    agree += 1
                else:
                    disagree += 1
            counts[verdict] += 1
            print("%3d %-7s %-26s %5d %-5s %4.0f s %2d tests  %s%s" %
                  (a.skip + done, verdict, m["file"], m["line"], m["kind"], time.time() - t1, len(tests), by, full),
                  flush=True)
            if verdict == "survived":
                survivors.append(m)
                print("      - %s\n      + %s" % (m["old"].strip(), m["new"].strip()), flush=True)
        finally:
            with open(path, "w") as f:
                f.write(orig)
            os.utime(path, None)
            if rebuild(tree, m["file"], a.j, log, programs) != 0:
                sys.exit("mutate-sample: the tree does not build after %s:%d was restored; see %s" %
                         (m["file"], m["line"], log))
    killed, surv = counts["killed"], counts["survived"]
    print("mutate-sample: seed %d: %d mutants built (%d did not compile), %d killed, %d survived "
          "(%d executed by no test); kill rate %.1f%% before equivalents are set aside; %.0f s" %
          (seed, done, counts["nobuild"], killed, surv, counts["nocover"],
           100.0 * killed / max(done, 1), time.time() - t0))
    if a.full:
        print("mutate-sample: subset vs whole suite on %d mutants: %d agree, %d disagree" %
              (agree + disagree, agree, disagree))
    if not a.work:
        shutil.rmtree(work, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
