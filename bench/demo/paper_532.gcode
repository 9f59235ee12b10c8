; The seed paper's experiment: X:Y:Z = 5000:3000:2000 steps (default 100 steps/mm),
; master X cruising at 50 kHz. F is the path feed: 50 mm at 3000 mm/s on X is a path of
; sqrt(50^2+30^2+20^2) mm = 61.644 mm at 61.644/50*3000*60 = 36986.484 mm/min.
G91
G1 X50 Y30 Z20 F36986.484
G1 X-50 Y-30 Z-20 F36986.484
