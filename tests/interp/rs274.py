#!/usr/bin/env python3
"""Run LinuxCNC's standalone RS274NGC interpreter (/usr/bin/rs274, Debian
package linuxcnc-uspace) on a G-code file, non-interactively, and print its
canonical commands normalised, one per line:

    tests/interp/rs274.py [--tool-table FILE] [--ini FILE] [--moves-only]
                          [--timeout S] FILE

Output (stdout): each canonical call without rs274's running counter and its
"N....." column, e.g. `STRAIGHT_FEED(10.0000, 5.0000, 0.0000, 0.0000, 0.0000, 0.0000)`;
a block that carried an N word is prefixed `N10 `. --moves-only keeps only
motion, feed, dwell and spindle calls.

On an interpreter error: stderr gets `rs274: error: MESSAGE` and
`rs274: line L: TEXT` (L found by matching the offending text rs274 echoes
against the file; `?` when it is not unique).

Exit status: 0 accepted; 1 interpreter error (or timeout); 2 usage error;
3 rs274 not installed. rs274 knows only X Y Z A B C: a U, V or W word is
"Bad character 'u' used" (its axis mask is fixed at XYZABC) -- use canon.py
for UVW programs.
"""

import os
import re
import shutil
import subprocess
import sys
import tempfile

RS274 = shutil.which("rs274") or "/usr/bin/rs274"
LINE_RE = re.compile(r"^\s*\d+ (N\.\.\.\.\.|N\d+\s*) (.*)$")
MOVES = ("STRAIGHT_TRAVERSE", "STRAIGHT_FEED", "ARC_FEED", "SET_FEED_RATE",
         "SET_FEED_MODE", "DWELL", "SET_SPINDLE_SPEED", "START_SPINDLE_CLOCKWISE",
         "START_SPINDLE_COUNTERCLOCKWISE", "STOP_SPINDLE_TURNING", "CHANGE_TOOL",
         "STRAIGHT_PROBE", "RIGID_TAP", "SELECT_PLANE", "USE_LENGTH_UNITS")

USAGE = ("usage: rs274.py [--tool-table FILE] [--ini FILE] [--moves-only] "
         "[--timeout S] FILE\n")


def usage_error(msg):
    sys.stderr.write("rs274.py: %s\n%s" % (msg, USAGE))
    sys.exit(2)


def main(argv):
    tbl = ini = None
    moves_only = False
    timeout = 60.0
    pos = []
    i = 0
    while i < len(argv):
        a = argv[i]
        if a in ("-h", "--help"):
            sys.stdout.write(USAGE)
            return 0
        if a in ("--tool-table", "--ini", "--timeout"):
            if i + 1 >= len(argv):
                usage_error("%s needs a value" % a)
            v = argv[i + 1]
            i += 1
            if a == "--tool-table":
                tbl = os.path.abspath(v)
            elif a == "--ini":
                ini = os.path.abspath(v)
            else:
                try:
                    timeout = float(v)
                except ValueError:
                    usage_error("--timeout wants a number")
        elif a == "--moves-only":
            moves_only = True
        elif a.startswith("-"):
            usage_error("unknown option %s" % a)
        else:
            pos.append(a)
        i += 1
    if len(pos) != 1:
        usage_error("need exactly one FILE")
    path = os.path.abspath(pos[0])
    if not os.path.isfile(path) or not os.access(path, os.R_OK):
        usage_error("cannot read %s" % pos[0])
    if not os.access(RS274, os.X_OK):
        sys.stderr.write("rs274.py: %s not found; install it: tests/interp/install.sh\n" % RS274)
        return 3

    # -g: batch mode (no menu). stdin from /dev/null: without -g rs274 asks
    # for a menu choice. Never use -n 0 ("continue"): on a program with no
    # M2/% it repeats the end-of-file error forever. Run in a scratch cwd
    # and HOME: rs274 creates (O_TRUNC) $HOME/.tool.mmap, the tool table a
    # running LinuxCNC session shares, so never let it touch the real one.
    cmd = [RS274, "-g"]
    if tbl:
        cmd += ["-t", tbl]
    if ini:
        cmd += ["-i", ini]
    cmd.append(path)
    tmp = tempfile.mkdtemp(prefix="rs274-py-")
    try:
        env = dict(os.environ, HOME=tmp)
        p = subprocess.run(cmd, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                           stderr=subprocess.PIPE, cwd=tmp, env=env, timeout=timeout)
    except subprocess.TimeoutExpired:
        sys.stderr.write("rs274: error: timeout after %gs (endless O-word loop?)\n" % timeout)
        return 1
    finally:
        shutil.rmtree(tmp, ignore_errors=True)

    out = p.stdout.decode("utf-8", "replace").splitlines()
    for raw in out:
        m = LINE_RE.match(raw)
        if not m:
            continue
        tag, call = m.group(1).strip(), m.group(2).strip()
        if moves_only and not call.startswith(MOVES):
            continue
        sys.stdout.write(("%s %s\n" % (tag, call)) if tag.startswith("N") and tag != "N....." else call + "\n")

    if p.returncode != 0:
        err = [l for l in p.stderr.decode("utf-8", "replace").splitlines()
               if l.strip() and l.strip() != "executing"]
        msg = err[0] if err else "rs274 exited %d" % p.returncode
        sys.stderr.write("rs274: error: %s\n" % msg)
        if len(err) > 1:
            text = err[1]
            with open(path, "rb") as fh:
                lines = fh.read().decode("utf-8", "replace").splitlines()
            hits = [n + 1 for n, l in enumerate(lines) if l == text]
            where = str(hits[0]) if len(hits) == 1 else "?"
            sys.stderr.write("rs274: line %s: %s\n" % (where, text))
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
