"""The biped as data: parameter files (read with limits, validated), the Pinocchio models built
from one parameter set, and the URDF for visualization tools.

Imports nothing else of the core.
"""
