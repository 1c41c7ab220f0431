; dialect_marlin.gcode after the filter the README describes: accepted
; M104 S200 ; dropped: printer-only M-code
; G28 ; dropped: Marlin homing has no LinuxCNC program equivalent
G21
G90
G1 X10 Y10 F1200
G4 P0.5 ; was G4 P500 (ms) -> seconds
; M107 ; dropped
M2 ; appended: LinuxCNC needs a program end
