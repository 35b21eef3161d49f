"""Values Kang, Huang & Yang (2023) report, copied from shared/reference; used to mark
figures only, never by the model."""

PAPER = {
    "shear_yield_mpa": 1194.0,  # Sec 4.2
    "max_pressure_angle_deg": 45.0,  # Sec 2.3
    "roller_radius_mm": 15.0,  # Sec 2.3
    "phi_max_bounds_deg": [23.0, 26.0],  # Eq 40
}
