//! Design level: single damper under harmonic excitation, effective fields, motion modes.
