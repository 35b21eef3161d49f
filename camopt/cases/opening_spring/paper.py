"""Values Ahn, Cho, Park & Kim report (Eq 6), copied from shared/reference; used to mark
figures only, never by the model."""

THETA_RAD = (-2.0783e-3, 8.5575e-2, 9.5343e-2)  # theta(t0), theta(tk), theta(ts)
THETADOT_T0_RAD_S = 8.9226
PAPER = {"theta_rad": list(THETA_RAD), "thetadot_t0_rad_s": THETADOT_T0_RAD_S}
