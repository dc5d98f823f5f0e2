"""Toroidal exemplar refinement: a coarse-to-fine nearest-patch field that carries the GAN's tileable
layout up to the source's resolution with real source texels. Beyond the paper.
"""
