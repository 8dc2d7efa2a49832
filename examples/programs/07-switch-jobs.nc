( Example 7 - Switching Camera Jobs Mid-Program.                                 )
( Shows: M284 selecting camera jobs; a 4-mark alignment with the coarse job,     )
( then a fine capture with the precise job at the part centre, in the aligned    )
( frame [the observed point is reported in program coordinates].                 )
( Use a coarse fiducial finder for the rough alignment, then switch )
( to a precise circle-fit job for the final inspection step.         )
G90 G20
T98 M6
M284 P1                  ( camera job 1 = coarse finder )
M280
G0 X0 Y0
M281
G0 X10.0 Y0
M281
G0 X10.0 Y6.0
M281
G0 X0 Y6.0
M281
M282                     ( apply alignment using job 1 captures )
M284 P2                  ( camera job 2 = precise circle fit )
G0 X5.0 Y3.0
M281                     ( fine measurement at part centre, aligned frame )
G69 G50 G52 X0 Y0
M30
