"""Values Clauss & Papalambros (1982) report (Table 1, Eq 92), copied from
shared/reference; used to mark figures only, never by the model."""

TABLE1_COILS = list(range(3, 43))
TABLE1_CLOSURE_TIME_MS = [21.74, 20.04, 19.24, 18.93, 18.9, 19.05, 19.32, 19.66, 20.06, 20.48,
                          20.93, 21.4, 21.87, 22.36, 22.84, 23.33, 23.81, 24.3, 24.78, 25.26,
                          25.73, 26.21, 26.68, 27.15, 27.61, 28.08, 28.54, 29.0, 29.45, 29.91,
                          30.37, 30.83, 31.29, 31.75, 32.21, 32.68, 33.16, 33.64, 34.14, 34.65]
PAPER = {"table1_coils": TABLE1_COILS, "table1_closure_time_ms": TABLE1_CLOSURE_TIME_MS,
         "optimum_coils": 7, "optimum_closure_time_ms": 18.9}

# Eq 92: the paper's optimum (7 coils) by the run's names, the reference design of show,
# report and compare
OPTIMUM = {"closure_time_ms": 18.9, "coils": 7, "sf_mm": 66.0, "sud_mm": 66.0, "s0_mm": 14.0,
           "r3_mm": 289.0, "r2_mm": 56.0, "xi": 0.0147, "omega_n_rad_s": 84.1,
           "k_n_per_m": 7400.0, "g_mm": 400.0, "theta3f_deg": 348.9, "theta30_deg": 354.4,
           "theta20_deg": 30.0}
