"""From dwell to dwell: the best connection of two slots, and the hops and segments of a move sequence."""
