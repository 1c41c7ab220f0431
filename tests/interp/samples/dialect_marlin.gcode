; Marlin-style output (3D printer / hot-end): rejected as-is
M104 S200 ; hot-end temperature: user M-code range, unknown to LinuxCNC
G28 ; Marlin: home all axes. LinuxCNC: go to the stored G28 position
G21
G90
G1 X10 Y10 F1200
G4 P500 ; Marlin: 500 ms. LinuxCNC would read 500 s
M107
