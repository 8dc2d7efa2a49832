%
( Grbl: as examples/programs/08-cam-job.nc, except the end: Grbl has no G68, G51   )
( or G52 [error:20], so M282 hands the fit to the sender, which maps every later   )
( move - the canned cycle, the subprogram's arcs, the G91 plunge - before it sends )
( it; M30 ends that mapping, not G69 G50 G52.                                       )
O0008 ( Example 8 - a CAM-style job on a 6 x 4 in plate, aligned by a 4-mark rectangle fit )
( Shows: what a post-processor writes - safety line, tool changes, spindle and coolant, )
( G43 tool lengths, a G81 drilling cycle, a pocket contour with arcs run as an M98       )
( subprogram at two depths, M30 - running in the frame M282 measured on the real part.  )
G17 G40 G49 G80 G90 G20 G94
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
( T1: 1/4 in drill - four corner holes )
T1 M6
S3000 M3
G43 H1 M8
G0 Z0.5
G0 X1.0 Y1.0
G98 G81 X1.0 Y1.0 Z-0.3 R0.1 F10.0
X5.0
Y3.0
X1.0
G80
M9
( T2: 1/8 in end mill - the slot with round ends around the part centre, two passes )
T2 M6
S12000 M3
G43 H2 M8
G0 X2.0 Y1.0
G0 Z0.1
G1 Z0 F20.0
M98 P100 L2
G0 Z0.5
M5 M9
G49
( M30 ends the sender's mapping of the moves: Grbl has no G69, G50 or G52 )
M30
O100 ( one pass of the slot, 0.05 in deeper than the last )
G91 G1 Z-0.05 F20.0
G90 G1 X4.0 F60.0
G3 X4.0 Y3.0 I0 J1.0
G1 X2.0
G3 X2.0 Y1.0 I0 J-1.0
M99
%
