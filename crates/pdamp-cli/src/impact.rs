//! `pdamp impact`: a single head-on impact from the contact laws.

use anyhow::{Result, anyhow};
use clap::{Args, ValueEnum};
use pdamp_dem::Material;
use pdamp_dem::impact::{ImpactLaw, ImpactRequest, Partner, checked_head_on_impact};

// The arguments of `pdamp impact` (the command's help is the variant's doc in `Command`).
#[derive(Args)]
pub(crate) struct ImpactArgs {
    /// Impact partner.
    #[arg(long, value_enum, default_value_t = PartnerArg::Wall)]
    partner: PartnerArg,
    /// Sphere radius, m.
    #[arg(long)]
    radius_m: f64,
    /// Young's modulus, Pa.
    #[arg(long)]
    youngs_modulus_pa: f64,
    /// Poisson's ratio.
    #[arg(long)]
    poisson_ratio: f64,
    /// Density, kg/m³.
    #[arg(long)]
    density_kg_m3: f64,
    /// Normal contact law.
    #[arg(long, value_enum, default_value_t = LawArg::Hertz)]
    law: LawArg,
    /// Coefficient of restitution (dissipative laws).
    #[arg(long, default_value_t = 1.0)]
    restitution: f64,
    /// Normal stiffness for the linear law, N/m (default: Hertz secant stiffness at max overlap).
    #[arg(long)]
    stiffness_n_m: Option<f64>,
    /// Impact velocity, m/s.
    #[arg(long)]
    velocity_m_s: f64,
}

#[derive(Clone, Copy, ValueEnum)]
enum PartnerArg {
    Wall,
    Sphere,
}

#[derive(Clone, Copy, ValueEnum)]
enum LawArg {
    Hertz,
    Gonthier,
    LankaraniNikravesh,
    Linear,
    HertzMindlin,
}

/// Runs `pdamp impact`: prints the measured and Hertz-theory values as JSON.
pub(crate) fn run(args: ImpactArgs) -> Result<()> {
    let ImpactArgs {
        partner,
        radius_m,
        youngs_modulus_pa,
        poisson_ratio,
        density_kg_m3,
        law,
        restitution,
        stiffness_n_m,
        velocity_m_s,
    } = args;
    let req = ImpactRequest {
        partner: match partner {
            PartnerArg::Wall => Partner::Wall,
            PartnerArg::Sphere => Partner::Sphere,
        },
        radius_m,
        material: Material::new("material", density_kg_m3, youngs_modulus_pa, poisson_ratio),
        law: match law {
            LawArg::Hertz => ImpactLaw::Hertz,
            LawArg::Gonthier => ImpactLaw::Gonthier,
            LawArg::LankaraniNikravesh => ImpactLaw::LankaraniNikravesh,
            LawArg::Linear => ImpactLaw::Linear,
            LawArg::HertzMindlin => ImpactLaw::HertzMindlin,
        },
        restitution,
        stiffness_n_m,
        velocity_m_s,
    };
    // The library names the input; the command line prints it as its flag.
    let r = checked_head_on_impact(&req).map_err(|e| match e.key {
        "result" | "material" => anyhow!("{}", e.message),
        key => anyhow!("--{} {}", key.replace('_', "-"), e.message),
    })?;
    println!("{}", serde_json::to_string_pretty(&r)?);
    Ok(())
}
