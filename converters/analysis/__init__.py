"""Analysis of any problem and method: periodic orbits, conduction modes, GDCM."""
