( Example 6 - Reading the Result with Pound Variables.                           )
( Shows: the pound-variable block - M281 writes the observed X/Y, width, height, )
( angle and score of the capture to #500.. [slot 0] and #508.. [slot 1], and     )
( G-code math uses them, here to set the G55 fixture offset.                     )
( Single-mark inspection: trigger and use the result in G-code math )
( Requires VisionPoundVarBase = 500 [default]. )
G90 G20
T98 M6
M280 ( begin run so M281 has somewhere to store the dot )
G0 X10.0 Y8.0
M281 ( capture; #500=obs X, #501=obs Y, #502=width, #503=height )
( Apply the deviation as a fixture offset on G55 )
G10 L2 P2 X[#500] Y[#501]
M30
