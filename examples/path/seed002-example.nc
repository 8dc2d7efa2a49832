(Seed 002, MachineMotion V2 path following: the Python example's GCODE_STRING.)
(Plan it: mach-vision plan examples/path/seed002-example.nc --accel 1000 --machine-units mm)
(Operational mode commands)
G90 ; Absolute position mode
G90.1 ; Absolute arc centre
G21 ; Use millimeter units
G17 ; XY plane arcs
G64 P0.5 ; Blend move mode, 0.5 mm tolerance

(Movement and output commands)
G0 X60 Y110 F1000 ; Travel move at 1000 mm/minute
M3 $1 ; Start tool 1 in clockwise direction
G1 X110 Y110
G2 X110 Y10 I100 J60 ; Clockwise arc
G1 X60 Y10
G2 X60 Y110 I60 J60
G4 P1.0 ; Dwell for 1 second
M5 $1 ; Stop tool 1
G0 X1 Y1
