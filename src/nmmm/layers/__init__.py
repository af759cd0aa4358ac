"""nmmm.layers — meso scale: pigment scattering (Mie), radiative transfer in the
pigmented film (Kubelka–Munk with Saunderson, adding–doubling), thin-film interference.

Shared by two authors: each adds only the import lines of their own modules below.
"""
from nmmm.layers.fresnel import brewster_angle, critical_angle, fresnel, n_cos_theta  # noqa: E402,F401  (thin films)
from nmmm.layers.thinfilm import Layer, Stack, StackResult  # noqa: E402,F401  (thin films)
