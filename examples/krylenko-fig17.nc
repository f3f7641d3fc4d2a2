%
O0017 (KRYLENKO FIG 17: INTERNAL TAPERS)
; Krylenko Fig. 16/17: internal tapers (boring bar), programmed as drawn
; compensate with: host-sim compensate examples/krylenko-fig17.nc --rn 0.4 --tip 2
G21 G18 G99
T0202
G50 S2500
G96 S120 M03
G00 X88 Z10 M08 ; safe approach
G00 X90 Z2
N10 G41 G01 Z0 F0.08
N20 X78            ; point 1
N30 X50 Z-14       ; point 2
N40 Z-34           ; point 3
N50 X28 Z-45       ; point 4
N60 X12            ; point 5
N70 Z-60
N80 G40 G00 X10
N90 Z10
M05 M09
M30
%
