"""Repeating textures (bricks, tiles, weaves): their lattice periods and a tile cut to whole periods
along minimum-error boundaries. Beyond the paper.
"""
