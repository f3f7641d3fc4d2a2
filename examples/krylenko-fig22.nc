%
O0022 (KRYLENKO FIG 22: RADII)
; Krylenko Fig. 21/22: radii R2 (convex), R3 (concave), R4 (convex)
; compensate with: host-sim compensate examples/krylenko-fig22.nc --rn 0.4 --tip 3
G21 G18 G99
T0101
G50 S2500
G96 S120 M03
G00 X10 Z10 M08 ; safe approach
G00 X0 Z2
N10 G42 G01 Z0 F0.1
N20 X8             ; point 2
N30 G03 X12 Z-2 R2 ; point 3
N40 G01 Z-14       ; point 4
N50 G02 X18 Z-17 R3 ; point 5
N60 G01 X30        ; point 6
N70 G03 X38 Z-21 R4 ; point 7
N80 G01 Z-30
N90 G40 G00 X45
M05 M09
M30
%
