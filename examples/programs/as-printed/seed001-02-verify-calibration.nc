( Vision alignment test - walks the 5-dot calibration sheet pattern )
( Sheet center = 0,0 in current work coords )
( Corners at (+/- 2.5, +/- 4.0) inch )
( Walk order: 1 -> 2 -> 3 -> 4 (4-point fit) -> 5 (center verify) )
G90 G20 G17 ( absolute, inches, XY plane )
G54 ( use whatever WCS is zeroed at sheet center )
T98 M6 ( camera tool )
M280 ( begin 4-point alignment run )
G0 X-2.5 Y-4.0 ( dot 1 - lower left )
M281
G0 X-2.5 Y4.0 ( dot 2 - upper left )
M281
G0 X2.5 Y4.0 ( dot 3 - upper right )
M281
G0 X2.5 Y-4.0 ( dot 4 - lower right )
M281
M282 ( solve + apply modal G51 / G68 / G52 )
G0 X0 Y0 ( dot 5 - center, post-fit verify )
M281 ( capture; pound vars #500..#507 show residual )
( Inspect #500 (X), #501 (Y) - both should be ~0 if fit is good. )
( To clear the transform when done: )
( G69 G50 G52 X0 Y0 )
M30
