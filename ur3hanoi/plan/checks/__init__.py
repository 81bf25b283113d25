"""What a plan must satisfy: joint limits, the vertical line, the suction's hold, clearances."""
