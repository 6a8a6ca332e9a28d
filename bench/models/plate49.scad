// The 49-hole plate, the same model as plate49.vp, for OpenSCAD.
difference() {
  cube([100, 100, 10]);
  for (i = [0:6], j = [0:6])
    translate([10 + 80 / 6 * i, 10 + 80 / 6 * j, -1]) cylinder(h = 12, r = 4, $fn = 64);
}
