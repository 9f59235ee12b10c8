; A CAM-style contour for the path picture (docs/bench.md): a rounded rectangle (arcs that
; keep their speed) around a zigzag (sharp corners that slow down), 1 mm deep, at F3000.
; 100 steps/mm; 6000 mm/min and 500 mm/s² on X and Y.
$100=100
$101=100
$102=100
$110=6000
$111=6000
$112=3000
$120=500
$121=500
$122=500
G21 G90 G17 G94
G0 X5 Y0 Z5
G1 Z-1 F600
G1 X35 F3000
G3 X40 Y5 I0 J5
G1 Y20
G3 X35 Y25 I-5 J0
G1 X5
G3 X0 Y20 I0 J-5
G1 Y5
G3 X5 Y0 I5 J0
G1 X10 Y20
G1 X15 Y5
G1 X20 Y20
G1 X25 Y5
G1 X30 Y20
G1 X35 Y5
G0 Z5
G0 X0 Y0
