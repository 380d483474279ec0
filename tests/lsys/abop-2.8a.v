tropism direction: 0,-1,0
initial elasticity: 0.22
line style: cylinder
contour sides: 8
