; One X move at F3000 with $120=2000 as a trapezoid: beside scurve_x60.gcode
$100=100
$110=36000
$120=2000
$41=0
G91
G1 X60 F3000
