"""validation.real_static — independent checks of ``tiltbench noise`` on real static IMU logs."""
