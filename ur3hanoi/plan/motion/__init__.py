"""How the arm moves: Ruckig trajectories, vertical paths, approach legs, via states and blends, sampling."""
