; The seed paper's move (paper_532.gcode) with the S-curve ramp ($41=1) instead of the
; trapezoid: the same counts and cruise, a smooth start and end of each acceleration.
$100=100
$101=100
$102=100
$110=36000
$111=36000
$112=36000
$120=10000
$121=10000
$122=10000
$41=1
G91
G1 X50 Y30 Z20 F36986.484
G1 X-50 Y-30 Z-20 F36986.484
