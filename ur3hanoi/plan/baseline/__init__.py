"""What a plan is measured against: stop-and-go between the same waypoints."""
