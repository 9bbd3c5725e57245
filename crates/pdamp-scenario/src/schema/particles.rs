//! The particle groups of a scenario: count or filling, size distribution, and how they are
//! placed (lattice, random insertion, drop-down with an inlet or the lid open, a bed file).

use pdamp_dem::ParameterError;
use pdamp_dem::generate::{Region, SizeDistribution};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// A group of particles.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ParticleGroupSpec {
    /// Material name.
    pub material: String,
    /// Number of particles (or give `filling`).
    #[serde(default)]
    pub count: Option<usize>,
    /// Number of particles from a filling ratio or a clearance [D Eq. 8.1].
    #[serde(default)]
    pub filling: Option<FillingSpec>,
    /// Size distribution.
    pub size: SizeDistribution,
    /// Where the particles start.
    pub placement: PlacementSpec,
    /// Initial velocity, m/s.
    #[serde(default)]
    pub initial_velocity_m_s: [f64; 3],
}

/// Particle number from the container's capacity $n_p^{max}$: either a filling ratio
/// $n_p/n_p^{max}$ or a clearance h to the lid, $n_p = n_p^{max}(1 - h/L)$ [D Eq. 8.1].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FillingSpec {
    /// Particles that fill the container completely, $n_p^{max}$.
    pub max_count: usize,
    /// Filling ratio $n_p / n_p^{max}$ in (0, 1].
    #[serde(default)]
    pub ratio: Option<f64>,
    /// Clearance h between bed and lid, m.
    #[serde(default)]
    pub clearance_m: Option<f64>,
    /// Inner container length L along the excitation, m (with `clearance_m`).
    #[serde(default)]
    pub container_length_m: Option<f64>,
}

impl ParticleGroupSpec {
    /// Number of particles of the group from `count` or `filling`.
    pub fn resolved_count(&self) -> Result<usize, ParameterError> {
        match (&self.count, &self.filling) {
            (Some(n), None) => Ok(*n),
            (None, Some(f)) => {
                if f.max_count == 0 {
                    return Err(ParameterError::from_message(
                        "filling.max_count must be > 0",
                    ));
                }
                let ratio = match (f.ratio, f.clearance_m, f.container_length_m) {
                    (Some(r), None, None) => {
                        if !(r > 0.0 && r <= 1.0) {
                            return Err(ParameterError::from_message(format!(
                                "filling.ratio must be in (0, 1], got {r}"
                            )));
                        }
                        r
                    }
                    (None, Some(h), Some(l)) => {
                        if !(l > 0.0 && h >= 0.0 && h < l) {
                            return Err(ParameterError::from_message(format!(
                                "filling: need 0 <= clearance_m < container_length_m, got {h} and {l}"
                            )));
                        }
                        1.0 - h / l
                    }
                    _ => {
                        return Err(ParameterError::from_message(
                            "filling: give either ratio, or clearance_m together with container_length_m",
                        ));
                    }
                };
                Ok((ratio * f.max_count as f64).round() as usize)
            }
            _ => Err(ParameterError::from_message(
                "count: give exactly one of `count` and `filling` in the group",
            )),
        }
    }
}

/// Initial placement of a particle group.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlacementSpec {
    /// `drop_down` (random insertion clear of every wall, falling in rounds under gravity: the
    /// dissertation's beds), `random` (random insertion clear of every wall, no fall), `grid`
    /// (simple cubic crystal), `tight` (hexagonal close-packed crystal) or `file` (a saved or
    /// imported bed).
    pub method: PlacementMethod,
    /// Region to fill (all methods but `file`), m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub region: Option<Region>,
    /// Gap between neighbouring spheres (lattices), m.
    #[serde(default)]
    pub gap_m: f64,
    /// For `random`: height of insertion layers (layer by layer), m.
    #[serde(default)]
    pub layer_height_m: Option<f64>,
    /// For `file`: the bed file, relative to the scenario file: a native bed of `pdamp settle`
    /// (`*.pdbed`, exact continuation), a LAMMPS/LIGGGHTS data file of `write_data`
    /// (`*.data`, `*.lmp`; SI units, `atom_style sphere` or `granular`) or a CSV file
    /// (`*.csv`: `x_m,y_m,z_m,radius_m[,vx_m_s,…]`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub path: Option<PathBuf>,
    /// For `file`: the format when the extension does not tell (`native`, `lammps`, `csv`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub format: Option<BedFormat>,
    /// For `file` with a LAMMPS data file: material name of atom type 1, 2, … (default: every
    /// atom gets the group's material).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub type_materials: Vec<String>,
    /// For `drop_down`: most insertion rounds (default 200).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_rounds: Option<usize>,
    /// For `drop_down`: longest fall of a round, s (default 0.5 s).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_round_duration_s: Option<f64>,
    /// For `drop_down`: a round's fall ends when the kinetic energy per particle is below this,
    /// J (default: 1 % of m g r of the mean particle).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub round_kinetic_energy_per_particle_j: Option<f64>,
    /// For `drop_down`: fill with the lid open and close it afterwards (D L3085, L3093), for
    /// containers whose clearance to the lid is less than a diameter.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub open_lid: Option<OpenLidSpec>,
    /// For `drop_down`: pour from an inlet over time instead of inserting in rounds.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub inlet: Option<InletSpec>,
}

/// `placement.inlet` of a `drop_down` group ([`pdamp_dem::drop_down::Inlet`]): the particles
/// are inserted into `region` at `rate_per_s` with `velocity_m_s` while the world runs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InletSpec {
    /// The inlet region inside the container, above the bed, m.
    pub region: Region,
    /// Particles per second of simulated time.
    pub rate_per_s: f64,
    /// Velocity of the inserted particles, m/s (default at rest).
    #[serde(default)]
    pub velocity_m_s: [f64; 3],
}

/// `placement.open_lid` of a `drop_down` group: the walls that end at the region's top are
/// extended by `headroom_m` while the particles pour in; then the lid closes onto the bed at
/// `close_speed_m_s`, pushing with at most the bed's weight, while the container is tapped
/// along −g at `tap_frequency_hz` with Γ = `tap_intensity` where given
/// ([`pdamp_dem::drop_down::OpenLid`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OpenLidSpec {
    /// How far the container is extended above its top while pouring, m.
    pub headroom_m: f64,
    /// Closing speed of the lid onto a bed that stands above the top, m/s (default 0.02).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub close_speed_m_s: Option<f64>,
    /// Longest closing before the preparation gives up, s (default 2).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_close_duration_s: Option<f64>,
    /// Tapping frequency while the lid closes, Hz (with `tap_intensity`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tap_frequency_hz: Option<f64>,
    /// Tapping acceleration amplitude over g, Γ (with `tap_frequency_hz`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tap_intensity: Option<f64>,
}

impl OpenLidSpec {
    /// Checks ranges; the message names the key under `key`.
    pub(super) fn validate(&self, key: &str) -> Result<(), ParameterError> {
        let check = |name: &str, v: f64, hi: f64, unit: &str| {
            if v.is_finite() && v > 0.0 && v <= hi {
                Ok(())
            } else {
                Err(ParameterError::from_message(format!(
                    "{key}.open_lid.{name} must be in (0, {hi}] {unit}, got {v}"
                )))
            }
        };
        check("headroom_m", self.headroom_m, 100.0, "m")?;
        if let Some(v) = self.close_speed_m_s {
            check("close_speed_m_s", v, 100.0, "m/s")?;
        }
        if let Some(v) = self.max_close_duration_s {
            check("max_close_duration_s", v, 1e3, "s")?;
        }
        match (self.tap_frequency_hz, self.tap_intensity) {
            (Some(f), Some(i)) => {
                check("tap_frequency_hz", f, 1e5, "Hz")?;
                check("tap_intensity", i, 1e3, "(Γ = A/g)")
            }
            (None, None) => Ok(()),
            _ => Err(ParameterError::from_message(format!(
                "{key}.open_lid.tap_frequency_hz: give tap_frequency_hz and tap_intensity together (or neither)"
            ))),
        }
    }

    /// The drop-down's settings.
    pub fn to_open_lid(&self) -> pdamp_dem::drop_down::OpenLid {
        pdamp_dem::drop_down::OpenLid {
            headroom_m: self.headroom_m,
            close_speed_m_s: self.close_speed_m_s.unwrap_or(0.02),
            max_close_duration_s: self.max_close_duration_s.unwrap_or(2.0),
            tapping: match (self.tap_frequency_hz, self.tap_intensity) {
                (Some(frequency_hz), Some(intensity)) => Some(pdamp_dem::drop_down::Tapping {
                    frequency_hz,
                    intensity,
                }),
                _ => None,
            },
        }
    }
}

impl PlacementSpec {
    /// `method` in `region` with every other key at its default.
    pub fn new(method: PlacementMethod, region: Region) -> Self {
        Self {
            method,
            region: Some(region),
            gap_m: 0.0,
            layer_height_m: None,
            path: None,
            format: None,
            type_materials: Vec::new(),
            max_rounds: None,
            max_round_duration_s: None,
            round_kinetic_energy_per_particle_j: None,
            open_lid: None,
            inlet: None,
        }
    }
}

/// Placement method.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PlacementMethod {
    /// Simple cubic lattice (a crystal).
    Grid,
    /// Hexagonal close packing (a crystal).
    Tight,
    /// Random without overlap, clear of every wall; no fall.
    Random,
    /// Random insertion clear of every wall, falling in rounds under gravity
    /// ([`pdamp_dem::drop_down`], D Sect. 2.1, Fig. 2.2c/d).
    DropDown,
    /// A saved or imported bed ([`PlacementSpec::path`]).
    File,
}

/// Format of a bed file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BedFormat {
    /// pdamp's own bed file (`pdamp settle`), with the state for an exact continuation.
    Native,
    /// LAMMPS/LIGGGHTS data file (`write_data`).
    Lammps,
    /// Plain CSV.
    Csv,
}

impl BedFormat {
    /// The format `format` says, or the one of the path's extension.
    pub fn of(path: &Path, format: Option<BedFormat>) -> Result<BedFormat, ParameterError> {
        if let Some(f) = format {
            return Ok(f);
        }
        match path
            .extension()
            .and_then(|e| e.to_str())
            .map(|e| e.to_ascii_lowercase())
            .as_deref()
        {
            Some("pdbed") => Ok(BedFormat::Native),
            Some("data" | "lmp" | "lammps") => Ok(BedFormat::Lammps),
            Some("csv") => Ok(BedFormat::Csv),
            _ => Err(ParameterError::from_message(format!(
                "cannot tell the bed format of '{}' from its extension; name it *.pdbed, \
                 *.data or *.csv, or set placement.format = \"native\" | \"lammps\" | \"csv\"",
                path.display()
            ))),
        }
    }
}
