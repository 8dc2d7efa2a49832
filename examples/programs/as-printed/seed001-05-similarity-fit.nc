( Locate a part by 3 fiducials (similarity fit - shift, rotate, uniform scale) )
G90 G20 G17
G54
T98 M6
M280 P3 ( 3-point similarity fit )
G0 X0 Y0
M281
G0 X8.0 Y0
M281
G0 X4.0 Y6.0
M281
M282 ( apply )
T1 M6
( ...cutting program... )
G69 G50 G52 X0 Y0
M30
