%
O0012 (KRYLENKO FIG 12: EXTERNAL TAPERS)
; Krylenko Fig. 11/12: external tapers, programmed as drawn
; compensate with: host-sim compensate examples/krylenko-fig12.nc --rn 0.4 --tip 3
G21 G18 G99
T0101
G50 S2500
G96 S120 M03
G00 X30 Z10 M08 ; safe approach
G00 X20 Z2
N10 G42 G01 Z0 F0.1
N20 X28            ; point 2
N30 X48 Z-10       ; point 3
N40 Z-46           ; point 4
N50 X68 Z-56       ; point 5
N60 X94            ; point 6
N70 X114 Z-66      ; point 7
N80 Z-80
N90 G40 G00 X120
M05 M09
M30
%
