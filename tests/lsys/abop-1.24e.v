angle increment: 25.7
initial line width: 0.4
line style: cylinder
contour sides: 6
