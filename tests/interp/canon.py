#!/usr/bin/python3
"""Run a G-code file through LinuxCNC's RS274NGC interpreter (the `gcode`
Python module of Debian's linuxcnc-uspace) and print what it did as JSON.

    /usr/bin/python3 tests/interp/canon.py [options] FILE [AXES]

AXES is the machine's axis letters (default XYZABCUVW), e.g. XYUV for a
4-axis hot-wire cutter, XYZ for a 3-axis mill, XYZA for a 4th-axis mill.
A word for an axis the machine lacks is an interpreter error ("Bad
character 'u' used"), as on a real LinuxCNC machine.

Exit status: 0 program accepted, 1 interpreter error (or harness timeout),
2 usage error (bad arguments, file not readable), 3 environment/internal
error (gcode module missing, a callback raised).

Units: the gcode module hands every linear value to its canon in inches
(it divides by 25.4 when the program is in G21); this script converts back,
so every linear value in the output is mm (feeds mm/min) and every angle
(A, B, C) is degrees, whatever G20/G21 the program used.

See README.md beside this file for the output format and the quirks.
"""

import json
import math
import os
import shutil
import sys
import tempfile
import time

DIST_PACKAGES = "/usr/lib/python3/dist-packages"
DEBIAN_PYTHON = "/usr/bin/python3"

try:
    import gcode  # noqa: E402
except ImportError:
    # The module is built for Debian's own python3.11; a pyenv/venv python
    # does not see dist-packages. Re-run ourselves under Debian's python.
    if (os.path.exists(DEBIAN_PYTHON)
            and os.path.realpath(sys.executable) != os.path.realpath(DEBIAN_PYTHON)
            and not os.environ.get("CANON_PY_REEXEC")):
        os.environ["CANON_PY_REEXEC"] = "1"
        os.execv(DEBIAN_PYTHON, [DEBIAN_PYTHON] + sys.argv)
    if os.path.isdir(DIST_PACKAGES) and DIST_PACKAGES not in sys.path:
        sys.path.append(DIST_PACKAGES)
    try:
        import gcode  # noqa: F811
    except ImportError as e:
        sys.stderr.write("canon.py: cannot import LinuxCNC's gcode module (%s); "
                         "install it: tests/interp/install.sh\n" % e)
        sys.exit(3)

MM_PER_INCH = 25.4
AXES = "XYZABCUVW"
TOOL_POCKETS = 1001  # CANON_POCKETS_MAX
LINEAR = set("XYZUVW")
# canon plane numbers (CANON_PLANE in canon.hh)
PLANES = {1: "XY", 2: "YZ", 3: "XZ", 4: "UV", 5: "VW", 6: "UW"}
# ARC_FEED(first_end, second_end, first_axis, second_axis, rotation,
#          axis_end_point, ...): which axis letter each of first/second/axis is.
ARC_AXES = {1: ("x", "y", "z"), 2: ("y", "z", "x"), 3: ("z", "x", "y")}
FEED_MODES = {930: "inverse_time", 940: "units_per_minute", 950: "units_per_rev"}
SPINDLE = {3: "cw", 4: "ccw", 5: "off"}
RESULTS = {0: "INTERP_OK", 1: "INTERP_EXIT", 2: "INTERP_EXECUTE_FINISH",
           3: "INTERP_ENDFILE", 4: "INTERP_FILE_NOT_OPEN", 5: "INTERP_ERROR"}

USAGE = """usage: canon.py [--axes AXES] [--machine-units mm|inch] [--init CODE]...
                [--block-delete] [--user-m N,N..] [--timeout SECONDS]
                [--max-moves N] [--indent N] FILE [AXES]

  AXES              axis letters of the machine, any of XYZABCUVW
                    (default XYZABCUVW); as a second positional or --axes
  --machine-units   units the interpreter starts in before the program
                    says G20/G21 (default mm, like a metric LinuxCNC
                    machine; the bare gcode module would start in inches)
  --init CODE       extra startup block run before the program (repeatable),
                    like [RS274NGC]RS274NGC_STARTUP_CODE
  --block-delete    turn the block-delete switch on ('/' lines skipped)
  --user-m N,N..    user M-codes (100-199) the machine has files for; any
                    other M1xx is an error, as on LinuxCNC without them
  --timeout S       give up after S seconds (default 60): O-word loops
                    can run forever
  --max-moves N     give up after N moves (default 1000000)
  --indent N        pretty-print the JSON (default: one line)
"""


def r6(v):
    """Round to 1e-6 (1 nm / 1 micro-degree); kills 25.4 round-trip noise."""
    v = round(v, 6)
    return 0.0 if v == 0 else v


def usage_error(msg):
    sys.stderr.write("canon.py: %s\n%s" % (msg, USAGE))
    sys.exit(2)


def parse_args(argv):
    opts = {"axes": None, "machine_units": "mm", "init": [], "block_delete": False,
            "timeout": 60.0, "max_moves": 1000000, "indent": None, "user_m": set()}
    pos = []
    i = 0
    while i < len(argv):
        a = argv[i]

        def val():
            if i + 1 >= len(argv):
                usage_error("%s needs a value" % a)
            return argv[i + 1]
        if a in ("-h", "--help"):
            sys.stdout.write(USAGE)
            sys.exit(0)
        elif a == "--axes":
            opts["axes"] = val(); i += 1
        elif a == "--machine-units":
            opts["machine_units"] = val(); i += 1
        elif a == "--init":
            opts["init"].append(val()); i += 1
        elif a == "--user-m":
            for tok in val().replace(" ", "").split(","):
                if not tok:
                    continue
                try:
                    n = int(tok[1:] if tok[:1] in "mM" else tok)
                except ValueError:
                    usage_error("--user-m wants numbers like 100,101")
                if not 100 <= n <= 199:
                    usage_error("user M-codes are 100..199, not %s" % tok)
                opts["user_m"].add(n)
            i += 1
        elif a == "--block-delete":
            opts["block_delete"] = True
        elif a == "--timeout":
            try:
                opts["timeout"] = float(val())
            except ValueError:
                usage_error("--timeout wants a number")
            i += 1
        elif a == "--max-moves":
            try:
                opts["max_moves"] = int(val())
            except ValueError:
                usage_error("--max-moves wants an integer")
            i += 1
        elif a == "--indent":
            try:
                opts["indent"] = int(val())
            except ValueError:
                usage_error("--indent wants an integer")
            i += 1
        elif a.startswith("--"):
            usage_error("unknown option %s" % a)
        else:
            pos.append(a)
        i += 1
    if not pos or len(pos) > 2:
        usage_error("need FILE and optionally AXES")
    if len(pos) == 2:
        if opts["axes"] is not None:
            usage_error("axes given twice")
        opts["axes"] = pos[1]
    if opts["axes"] is None:
        opts["axes"] = AXES
    axes = opts["axes"].upper()
    if not axes or any(c not in AXES for c in axes) or len(set(axes)) != len(axes):
        usage_error("bad axis list %r: use letters from XYZABCUVW, each once" % opts["axes"])
    opts["axes"] = "".join(c for c in AXES if c in axes)
    if opts["machine_units"] not in ("mm", "inch"):
        usage_error("--machine-units is mm or inch")
    if opts["timeout"] <= 0:
        usage_error("--timeout must be positive")
    opts["file"] = pos[0]
    return opts


class TooManyMoves(Exception):
    pass


class UserMRejected(Exception):
    pass


def setup_tool_table(home):
    """Give the interpreter a tool table: tools 1..1000 in pockets 1..1000,
    zero offsets and diameters, spindle (pocket 0) empty.

    In Debian 12's linuxcnc 2.9.0~pre1 the interpreter keeps its tool table
    in a shared mmap ($HOME/.tool.mmap) that only a running LinuxCNC (or
    rs274) creates; gcode.parse does not, and any T word then segfaults
    inside libtooldata (tooldata_find_index_for_tool). So create the mmap
    ourselves, in a private HOME, through libtooldata's own functions.
    """
    import ctypes

    class CanonToolTable(ctypes.Structure):  # struct CANON_TOOL_TABLE, 112 bytes
        _fields_ = [("toolno", ctypes.c_int), ("pocketno", ctypes.c_int),
                    ("offset", ctypes.c_double * 9), ("diameter", ctypes.c_double),
                    ("frontangle", ctypes.c_double), ("backangle", ctypes.c_double),
                    ("orientation", ctypes.c_int)]
    os.environ["HOME"] = home  # tool_mmap_fname() reads HOME on first use
    lib = ctypes.CDLL("libtooldata.so.0")  # the copy librs274 already loaded
    creator = lib._Z17tool_mmap_creatorPK13EMC_TOOL_STATi  # tool_mmap_creator(NULL, 0)
    creator.argtypes = [ctypes.c_void_p, ctypes.c_int]
    put = lib._Z12tooldata_put16CANON_TOOL_TABLEi  # tooldata_put(CANON_TOOL_TABLE, int)
    put.argtypes = [CanonToolTable, ctypes.c_int]
    if creator(None, 0) != 0:
        raise RuntimeError("tool_mmap_creator failed")
    empty = CanonToolTable()
    empty.toolno = -1
    put(empty, 0)
    for i in range(1, TOOL_POCKETS):
        t = CanonToolTable()
        t.toolno = i
        t.pocketno = i
        put(t, i)


def axis_mask(axes):
    return sum(1 << AXES.index(c) for c in axes)


class Canon:
    """The callback object gcode.parse drives (the methods its C code calls)."""

    def __init__(self, opts, parameter_file):
        self.parameter_file = parameter_file  # read by the interpreter as an attribute
        self.mask = axis_mask(opts["axes"])
        self.machine_units = opts["machine_units"]
        self.block_delete = opts["block_delete"]
        self.deadline = time.monotonic() + opts["timeout"]
        self.timed_out = False
        self.max_moves = opts["max_moves"]
        self.too_many = False
        self.allowed_user_m = opts["user_m"]
        self.user_m_rejected = None
        self.seq = 0                 # line of the last next_line() call
        self.metric = opts["machine_units"] == "mm"
        self.feed_mode = "units_per_minute"
        self.feed_raw = None         # last set_feed_rate value as the module gave it
        self.feed_metric = self.metric
        self.plane = 1
        # position in the module's units: inches for XYZUVW, degrees for ABC
        self.pos = [0.0] * 9
        self.spindle_state = None
        self.moves = []
        self.dwells = []
        self.spindle = []
        self.comments = []
        self.messages = []
        self.tools = []
        self.offsets = []
        self.user_m = []
        self.line_modes = {}

    # --- queries ------------------------------------------------------
    def get_axis_mask(self):
        return self.mask

    def get_external_length_units(self):
        # machine units per mm: 1.0 for a metric machine, 1/25.4 for inch
        return 1.0 if self.machine_units == "mm" else 1.0 / MM_PER_INCH

    def get_external_angular_units(self):
        return 1.0

    def get_block_delete(self):
        return self.block_delete

    def get_tool(self, pocket):
        # every pocket N holds tool N with zero offsets, so any T word is known;
        # pocket 0 (the spindle) starts empty.
        toolno = -1 if pocket == 0 else pocket
        return (toolno, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0)

    def check_abort(self):
        if time.monotonic() > self.deadline:
            self.timed_out = True
            return True
        return False

    # --- per line state -----------------------------------------------
    def next_line(self, st):
        prev = self.seq
        self.seq = st.sequence_number
        if self.seq <= 0:
            return  # the state before the first line is all zeros
        if st.units in (200, 210):
            self.metric = st.units == 210
        if st.feed_mode in FEED_MODES:
            self.feed_mode = FEED_MODES[st.feed_mode]
        state = SPINDLE.get(st.spindle)
        if state is not None:
            cur = (state, r6(st.speed))
            if cur != self.spindle_state:
                # a first "off, 0" is just the power-on state: don't report it
                if not (self.spindle_state is None and cur == ("off", 0.0)):
                    # the module reports no spindle calls, only the state at
                    # the first canon call of each line: the M3/M4/M5/S was on
                    # a line in [since_line, line]
                    self.spindle.append({"line": self.seq, "since_line": max(prev, 1),
                                         "state": state, "speed": cur[1]})
                self.spindle_state = cur

    def comment(self, text):
        # G93/G94/G95 make the interpreter emit these; catch the mode here
        # because the state passed to next_line can predate the mode change
        # when the G93 shares its line with the move.
        if text.startswith("interpreter: feed mode set to"):
            if "inverse time" in text:
                self.feed_mode = "inverse_time"
            elif "per minute" in text:
                self.feed_mode = "units_per_minute"
            elif "per revolution" in text:
                self.feed_mode = "units_per_rev"
            return
        self.comments.append({"line": self.seq, "text": text})

    def message(self, text):
        self.messages.append({"line": self.seq, "text": text})

    # --- modal settings ---------------------------------------------------
    def set_plane(self, plane):
        self.plane = plane

    def set_feed_rate(self, rate):
        self.feed_raw = rate
        self.feed_metric = self.metric

    def set_traverse_rate(self, rate):
        pass

    def set_xy_rotation(self, theta):
        if theta:
            self.offsets.append({"line": self.seq, "kind": "xy_rotation", "degrees": r6(theta)})

    def set_g5x_offset(self, index, x, y, z, a, b, c, u=0.0, v=0.0, w=0.0):
        vals = (x, y, z, a, b, c, u, v, w)
        if any(vals):
            rec = {"line": self.seq, "kind": "g5x", "index": index}
            rec.update(self._axes_dict(vals))
            self.offsets.append(rec)

    def set_g92_offset(self, x, y, z, a, b, c, u=0.0, v=0.0, w=0.0):
        vals = (x, y, z, a, b, c, u, v, w)
        if any(vals):
            rec = {"line": self.seq, "kind": "g92"}
            rec.update(self._axes_dict(vals))
            self.offsets.append(rec)

    def tool_offset(self, *args):
        pass

    def change_tool(self, pocket):
        self.tools.append({"line": self.seq, "tool": pocket})

    def user_defined_function(self, num, p, q):
        # the module accepts every M100-M199; a real LinuxCNC (and rs274)
        # says "Unknown m code used" unless USER_M_PATH has a file for it.
        # num is the index into USER_DEFINED_FUNCTION: M100 is 0.
        num = num + 100 if num < 100 else num
        if num not in self.allowed_user_m:
            self.user_m_rejected = (self.seq, num)
            raise UserMRejected(num)
        self.user_m.append({"line": self.seq, "m": num, "p": r6(p), "q": r6(q)})

    def dwell(self, seconds):
        self.dwells.append({"line": self.seq, "seconds": r6(seconds)})

    # --- motion -----------------------------------------------------------
    def _axes_dict(self, vals):
        out = {}
        for letter, v in zip(AXES, vals):
            out[letter.lower()] = r6(v * MM_PER_INCH if letter in LINEAR else v)
        return out

    def _feed_for(self, rotary_only):
        if self.feed_raw is None:
            return None
        # the module divides every feed by 25.4 when the program is metric;
        # linear feeds: value is then in/min either way -> *25.4 gives mm/min.
        # A pure rotary move's feed is deg/min: only undo the module's /25.4.
        if rotary_only:
            return self.feed_raw * MM_PER_INCH if self.feed_metric else self.feed_raw
        return self.feed_raw * MM_PER_INCH

    @staticmethod
    def _straight_length(p0, p1):
        """The interpreter's own length rule (interp_find.cc): XYZ distance if
        any of XYZ moves, else UVW distance, else ABC distance."""
        def dist(idx, scale):
            return math.sqrt(sum(((p1[i] - p0[i]) * scale) ** 2 for i in idx))
        tiny = 1e-7
        if any(abs(p1[i] - p0[i]) > tiny for i in (0, 1, 2)):
            return dist((0, 1, 2), MM_PER_INCH), False
        if any(abs(p1[i] - p0[i]) > tiny for i in (6, 7, 8)):
            return dist((6, 7, 8), MM_PER_INCH), False
        return dist((3, 4, 5), 1.0), True

    def _count(self):
        if len(self.moves) >= self.max_moves:
            # the module swallows callback exceptions into a RuntimeError
            # ("parse_file interp_error"), so leave a flag as well
            self.too_many = True
            raise TooManyMoves()

    def _move(self, kind, vals):
        self._count()
        p0 = self.pos
        p1 = list(vals)
        rec = {"kind": kind, "line": self.seq}
        rec.update(self._axes_dict(p1))
        if kind == "feed":
            length, rotary = self._straight_length(p0, p1)
            self._add_feed(rec, length, rotary)
        self.moves.append(rec)
        self.pos = p1

    def _add_feed(self, rec, length, rotary):
        feed = self._feed_for(rotary)
        rec["feed"] = None if feed is None else r6(feed)
        rec["feed_mode"] = self.feed_mode
        rec["length"] = r6(length)
        if feed and feed > 0:
            if self.feed_mode == "units_per_rev":
                rec["duration_s"] = None
            else:
                rec["duration_s"] = r6(60.0 * length / feed)
        else:
            rec["duration_s"] = None
        if self.feed_mode == "inverse_time":
            # the interpreter turned F into feed = max(0.1, length * F)
            rec["inverse_time"] = r6(feed / length) if (feed and length > 0) else None

    def straight_traverse(self, x, y, z, a, b, c, u, v, w):
        self._move("traverse", (x, y, z, a, b, c, u, v, w))

    def straight_feed(self, x, y, z, a, b, c, u, v, w):
        self._move("feed", (x, y, z, a, b, c, u, v, w))

    def straight_probe(self, x, y, z, a, b, c, u, v, w):
        self._move("probe", (x, y, z, a, b, c, u, v, w))

    def rigid_tap(self, x, y, z):
        self._count()
        rec = {"kind": "rigid_tap", "line": self.seq,
               "x": r6(x * MM_PER_INCH), "y": r6(y * MM_PER_INCH), "z": r6(z * MM_PER_INCH)}
        self.moves.append(rec)

    def arc_feed(self, first_end, second_end, first_axis, second_axis, rotation,
                 axis_end_point, a, b, c, u, v, w):
        self._count()
        names = ARC_AXES.get(self.plane)
        p0 = self.pos
        if names is None:  # the interpreter refuses arcs in UV/UW/VW planes
            raise RuntimeError("arc_feed in plane %r" % self.plane)
        idx = {n: "xyz".index(n) for n in names}
        p1 = list(p0)
        p1[idx[names[0]]] = first_end
        p1[idx[names[1]]] = second_end
        p1[idx[names[2]]] = axis_end_point
        p1[3:9] = [a, b, c, u, v, w]
        s1, s2 = p0[idx[names[0]]], p0[idx[names[1]]]
        radius = math.hypot(s1 - first_axis, s2 - second_axis)
        # find_turn(): signed angle swept, rotation = +-turns (+ is CCW)
        alpha = math.atan2(s2 - second_axis, s1 - first_axis)
        beta = math.atan2(second_end - second_axis, first_end - first_axis)
        if rotation > 0:
            if beta <= alpha:
                beta += 2 * math.pi
            theta = (beta - alpha) + (rotation - 1) * 2 * math.pi
        else:
            if alpha <= beta:
                alpha += 2 * math.pi
            theta = (beta - alpha) + (rotation + 1) * 2 * math.pi
        dz = (axis_end_point - p0[idx[names[2]]]) * MM_PER_INCH
        arc_len = abs(radius * theta) * MM_PER_INCH
        length = math.hypot(arc_len, dz)
        rec = {"kind": "arc", "line": self.seq}
        rec.update(self._axes_dict(p1))
        rec["start"] = self._axes_dict(p0)
        rec["plane"] = PLANES[self.plane]
        rec["centre"] = {names[0]: r6(first_axis * MM_PER_INCH),
                         names[1]: r6(second_axis * MM_PER_INCH)}
        rec["rotation"] = rotation
        rec["direction"] = "ccw" if rotation > 0 else "cw"
        rec["turns"] = abs(rotation)
        rec["radius"] = r6(radius * MM_PER_INCH)
        rec["sweep_deg"] = r6(math.degrees(theta))
        self._add_feed(rec, length, False)
        self.moves.append(rec)
        self.pos = p1


def main(argv):
    opts = parse_args(argv)
    path = opts["file"]
    if not os.path.isfile(path) or not os.access(path, os.R_OK):
        usage_error("cannot read %s" % path)
    with open(path, "rb") as fh:
        lines = fh.read().decode("utf-8", "replace").splitlines()

    tmp = tempfile.mkdtemp(prefix="canon-py-")
    try:
        # the interpreter reads and rewrites (with a .bak) its parameter file;
        # give it an empty one of its own so nothing is written anywhere else
        param = os.path.join(tmp, "rs274ngc.var")
        open(param, "w").close()
        canon = Canon(opts, param)
        init = ["G21" if opts["machine_units"] == "mm" else "G20"] + opts["init"]
        old_home = os.environ.get("HOME")
        try:
            setup_tool_table(tmp)
        except Exception as e:
            sys.stderr.write("canon.py: cannot set up the tool table (%s: %s)\n" % (type(e).__name__, e))
            return 3
        # the module's C code writes "!!!" diagnostics to fd 2 when a callback
        # raises; catch fd 2 during the parse and pass on only other lines
        errlog = os.path.join(tmp, "stderr.txt")
        sys.stderr.flush()
        saved_fd2 = os.dup(2)
        fd = os.open(errlog, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
        os.dup2(fd, 2)
        os.close(fd)
        try:
            # list form: gcode.parse(file, canon, [startup blocks...]);
            # the older form is gcode.parse(file, canon, unitcode, initcode)
            result, seq = gcode.parse(os.path.abspath(path), canon, init)
        except KeyboardInterrupt:
            if not canon.timed_out:
                raise
            result, seq = None, canon.seq
        except Exception as e:  # a callback raised: our bug, not the program's
            if canon.too_many:
                result, seq = "too_many_moves", canon.seq
            elif canon.user_m_rejected:
                result, seq = "user_m", canon.seq
            else:
                sys.stderr.write("canon.py: internal error: %s: %s\n" % (type(e).__name__, e))
                return 3
        finally:
            sys.stderr.flush()
            os.dup2(saved_fd2, 2)
            os.close(saved_fd2)
            with open(errlog, "rb") as fh:
                for l in fh.read().decode("utf-8", "replace").splitlines():
                    if not l.startswith("!!!"):
                        sys.stderr.write(l + "\n")
            if old_home is None:
                os.environ.pop("HOME", None)
            else:
                os.environ["HOME"] = old_home
        error = None
        truncated = False
        if result == "user_m":
            line, num = canon.user_m_rejected
            error = {"line": line, "code": None,
                     "message": "Unknown m code used: M%d (user M-code with no file in "
                                "USER_M_PATH; allow it with --user-m %d)" % (num, num)}
            result = None
        elif result is None or result == "too_many_moves":
            why = ("harness timeout after %gs" % opts["timeout"] if result is None
                   else "harness limit of %d moves reached" % opts["max_moves"])
            error = {"line": canon.seq, "code": None,
                     "message": why + " (endless O-word loop?)"}
            result = None
            truncated = len(canon.moves) > 1000
            del canon.moves[1000:]
        elif result > gcode.MIN_ERROR:
            # strerror returns the text of the interpreter's last error (it
            # segfaults if called before any parse). The seq parse returns is
            # one past the failing line for errors found while reading a
            # line, so use the line of the last next_line() call, which the
            # module makes for the failing line itself.
            line = canon.seq if canon.seq > 0 else seq
            error = {"line": line, "code": result, "message": gcode.strerror(result),
                     "parse_seq": seq}
        if error is not None and error["line"] and 0 < error["line"] <= len(lines):
            error["text"] = lines[error["line"] - 1]
        out = {
            "ok": error is None,
            "file": path,
            "axes": opts["axes"],
            "units": {"linear": "mm", "angular": "deg", "feed": "mm/min (deg/min for pure A/B/C moves)"},
            "result": None if result is None else {"code": result, "name": RESULTS.get(result, str(result))},
            "error": error,
            "moves": canon.moves,
            "moves_truncated": truncated,
            "dwells": canon.dwells,
            "spindle": canon.spindle,
            "tools": canon.tools,
            "comments": canon.comments,
            "messages": canon.messages,
            "offsets": canon.offsets,
            "user_m": canon.user_m,
        }
        sys.stdout.write(json.dumps(out, indent=opts["indent"]) + "\n")
        return 0 if error is None else 1
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
