"""The drone: 6-DoF body motion and the IMU that measures it."""
