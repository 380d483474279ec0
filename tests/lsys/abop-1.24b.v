angle increment: 20
initial line width: 0.15
line style: cylinder
contour sides: 6
