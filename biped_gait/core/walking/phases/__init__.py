"""The walk's phases (``phase.Phase``: motion, guard, reset): the paper's ballistic single support
and impulsive double support (``impulsive``), and the double support walked as torque pulses
around the impact (``pulses``)."""
