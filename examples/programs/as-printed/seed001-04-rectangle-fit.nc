( Locate a 6 x 4 in part by its 4 corner fiducials, then run the cut )
( Operator drops the part on the fixture roughly square; fiducials )
( are at the nominal corners (0,0), (6,0), (6,4), (0,4). )
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
( At end of program, cancel the transform: )
G69 G50 G52 X0 Y0
M30
