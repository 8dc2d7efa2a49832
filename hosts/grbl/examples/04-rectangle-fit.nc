( Grbl: as examples/programs/04-rectangle-fit.nc, except the last lines: Grbl has )
( no G68, G51 or G52 [error:20], so M282 hands the whole fit, scale included, to   )
( the sender, which maps every later move; M30 ends that mapping, not G69 G50 G52. )
( Example 4 - 4-Point Rectangle Fit on a Production Part.                       )
( Shows: M280 / four M281 captures / M282 emitting G52, G68 and G51 with separate )
( X and Y scale; the cut below then runs in the corrected frame - its arcs become )
( polylines when the two scales differ.                                           )
( Locate a 6 x 4 in part by its 4 corner fiducials, then run the cut )
( Operator drops the part on the fixture roughly square; fiducials )
( are at the nominal corners [0,0], [6,0], [6,4], [0,4]. )
G90 G20 G17
G54
T98 M6 ( camera tool )
M280 ( default 4-point rectangle fit )
G0 X0 Y0
M281 ( fid 1 )
G0 X6.0 Y0
M281 ( fid 2 )
G0 X6.0 Y4.0
M281 ( fid 3 )
G0 X0 Y4.0
M281 ( fid 4 )
M282 ( solve and apply modal transform )
T1 M6 ( swap to cutter )
( ...your normal cutting program in part-design coords... )
( ...G51/G68/G52 modally re-map every move to the actual part... )
( A short demo cut: a 4 x 2 in slot with round ends around the part centre )
G0 Z0.25
G0 X2.0 Y1.0
M3
G1 Z-0.05 F20.0
G1 X4.0 F60.0
G3 X4.0 Y3.0 I0 J1.0
G1 X2.0
G3 X2.0 Y1.0 I0 J-1.0
G0 Z0.25
M5
( At end of program, M30 ends the sender's mapping of the moves )
M30
