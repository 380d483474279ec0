angle increment: 20
initial line width: 0.4
line style: cylinder
contour sides: 6
