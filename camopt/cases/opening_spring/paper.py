"""Values Ahn, Cho, Park & Kim report (Eq 6), copied from shared/reference; used to mark
figures only, never by the model."""

PAPER = {"theta_rad": [-2.0783e-3, 8.5575e-2, 9.5343e-2], "thetadot_t0_rad_s": 8.9226}
