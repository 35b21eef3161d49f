"""Pure-numpy physics shared by the cases: springs, linkages, cams, contact, dynamics.

Functions of arrays in SI units; they broadcast over a population and samples.
"""
