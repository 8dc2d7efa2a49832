( Vision K-matrix calibration - cal sheet 1 )
( 1. Tape sheet flat, X+ right / Y+ up )
( 2. Spindle tool active, jog over sheet CENTER, zero X and Y )
( 3. Camera tool active, jog over START dot (lower-left -2.5,-4.0) )
G90 G20 G17 ( absolute, inches, XY plane )
G54
T98 M6 ( camera tool - change number to match your setup )
M283 C1 ( walk sheet 1, solve K, write camera tool offset )
M30
