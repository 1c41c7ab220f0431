"""Pronterface's build-time estimate of a G-code file (Printrun's gcoder, the method behind
seed 002 Table 4): prints the duration in seconds, as Pronterface shows it (whole seconds)."""
import sys

from printrun import gcoder

with open(sys.argv[1]) as f:
    gcode = gcoder.GCode(f.readlines())
layers, duration = gcode.estimate_duration()
print(duration.total_seconds(), layers)
