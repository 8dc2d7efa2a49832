( Quick K calibration from a single dot of known diameter )
( Dot must be in the FOV when M283 Q runs.                 )

G90 G20
T98 M6
M283 Q0.5         ( half-inch printed dot )

M30
