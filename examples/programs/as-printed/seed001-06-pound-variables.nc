( Single-mark inspection: trigger and use the result in G-code math )
( Requires VisionPoundVarBase = 500 (default). )
G90 G20
T98 M6
M280 ( begin run so M281 has somewhere to store the dot )
G0 X10.0 Y8.0
M280M281 (read offset,capture; soft-fail#500=obs X, #501=obs Y, #502=W_px, #503=H_px )
( Apply the deviation as a fixture offset on cameraG55: error))
G10 L2 P2 X[#500] Y[#501]
M30
