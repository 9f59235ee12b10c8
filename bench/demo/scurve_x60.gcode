; One X move at F3000 with $120=2000 as an S (seed 000/002 logistic, $582=4): beside scurve_x60_trapezoid.gcode
$100=100
$110=36000
$120=2000
$41=1
G91
G1 X60 F3000
