; The seed paper's experiment: X:Y:Z = 5000:3000:2000 steps (100 steps/mm, set below),
; master X cruising at 50 kHz. F is the path feed: 50 mm at 3000 mm/s on X is a path of
; sqrt(50^2+30^2+20^2) mm = 61.644 mm at 61.644/50*3000*60 = 36986.484 mm/min.
; The paper's bench settings (the firmware's defaults suit a small gantry): 100 steps/mm,
; 36 000 mm/min and 10 000 mm/s² on X, Y and Z.
$100=100
$101=100
$102=100
$110=36000
$111=36000
$112=36000
$120=10000
$121=10000
$122=10000
G91
G1 X50 Y30 Z20 F36986.484
G1 X-50 Y-30 Z-20 F36986.484
