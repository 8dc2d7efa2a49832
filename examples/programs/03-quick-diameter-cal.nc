( Example 3 - Quick Diameter Cal: M283 Q from one dot of known diameter.         )
( Shows: K = diag[d/width_px, d/height_px] after the axis-detect bump; no tool    )
( offset is written. Less exact than M283 C1 [it cannot see camera rotation].    )
( Quick K calibration from a single dot of known diameter )
( Dot must be in the FOV when M283 Q runs. )
G90 G20
T98 M6
M283 Q0.5 ( half-inch printed dot )
M30
