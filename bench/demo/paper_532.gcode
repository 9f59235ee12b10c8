; Placeholder 5:3:2 demo (numbers to be replaced by the paper's lines).
G91
G1 X50 Y30 Z20 F600
G1 X-50 Y-30 Z-20 F600
