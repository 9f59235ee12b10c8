; 5:3:2 again with the master at 200 kHz: 1 µs pulses and at least 1 µs low (fine for A4988,
; TMC2209; not for DRV8825 or TB6600), faster rate and acceleration limits, then the same move
; as the paper.
$0=1
$100=100
$101=100
$102=100
$110=150000
$111=150000
$112=150000
$120=100000
$121=100000
$122=100000
G91
G1 X50 Y30 Z20 F147945.936
G1 X-50 Y-30 Z-20 F147945.936
