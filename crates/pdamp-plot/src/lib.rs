//! Plots (PNG and SVG) of effective-field maps, decay curves and FRFs.
