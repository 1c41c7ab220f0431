$H
(GRBL: the line above is a GRBL system command, not G-code)
G21 G90 G94
G0 X0 Y0
M3 S1000
G4 P0.5
G1 X10 Y0 F300
M5
M2
