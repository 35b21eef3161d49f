"""Values Yan, Chen, Yan & Hang (2023) report (Sec 4.4), copied from shared/reference;
used to mark figures only, never by the model."""

PAPER = {"peak_torque_nm": 7.72, "clearance_angle_rad": 1.72, "screw_peak_torque_nm": 19.06}
