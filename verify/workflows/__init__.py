"""Work on data: estimate, norm calibration, diagnose, simulate, identify, realised plans, remount."""
