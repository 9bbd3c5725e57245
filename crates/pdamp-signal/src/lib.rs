//! Signal analysis: harmonic amplitudes, complex power method, decay and FRF evaluation.
