"""nmmm.layers — meso scale: pigment scattering (Mie), radiative transfer in the
pigmented film (Kubelka–Munk with Saunderson, adding–doubling), thin-film interference.

Shared by two authors: each adds only the import lines of their own modules below.
"""
