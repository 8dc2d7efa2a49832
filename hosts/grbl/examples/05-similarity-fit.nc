( Grbl: as examples/programs/05-similarity-fit.nc, except the last lines: Grbl has )
( no G68, G51 or G52 [error:20], so M282 hands the fit to the sender, which maps   )
( every later move, arcs exact; M30 ends that mapping, not G69 G50 G52.            )
( Example 5 - 3-Point Similarity Fit.                                            )
( Shows: M280 P3 - shift, rotation and one uniform scale from three fiducials;   )
( M282 emits G51 with equal X and Y factors, so arcs stay exact arcs.             )
( Locate a part by 3 fiducials [similarity fit - shift, rotate, uniform scale] )
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
( A short demo cut: a 1 in radius circle around the triangle's centroid )
G0 Z0.25
G0 X5.0 Y2.0
M3
G1 Z-0.05 F20.0
G2 X5.0 Y2.0 I-1.0 J0 F60.0
G0 Z0.25
M5
( M30 ends the sender's mapping of the moves )
M30
