angle increment: 22.5
initial line width: 0.4
line style: cylinder
contour sides: 6
