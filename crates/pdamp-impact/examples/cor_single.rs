//! One FE impact, printed: `cargo run --release -p pdamp-impact --example cor_single -- SPHERE WALL R V MESH`
//! (materials: s235, al6060, saa9579, elastic-s235; wall `sphere` = identical sphere).
use pdamp_impact::study::hertz_pair;
use pdamp_impact::{FeOptions, Material, MeshDensity, Partner, simulate_impact};

fn mat(n: &str) -> Material {
    match n {
        "elastic-s235" => Material::s235().as_elastic(),
        "elastic-al6060" => Material::al6060().as_elastic(),
        _ => Material::builtin(n).expect("material"),
    }
}

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let sphere = mat(a.get(1).map_or("elastic-s235", |s| s));
    let wall = a.get(2).map_or("elastic-s235", |s| s);
    let partner = if wall == "sphere" {
        Partner::Sphere
    } else {
        Partner::Wall(mat(wall))
    };
    let r: f64 = a.get(3).map_or(0.015, |s| s.parse().unwrap());
    let v: f64 = a.get(4).map_or(1.0, |s| s.parse().unwrap());
    let d = match a.get(5).map_or("medium", |s| s) {
        "coarse" => MeshDensity::Coarse,
        "fine" => MeshDensity::Fine,
        _ => MeshDensity::Medium,
    };
    let opts = FeOptions::with_density(d);
    let res = simulate_impact(&sphere, &partner, r, v, &opts);
    let h = hertz_pair(&sphere, &partner, r);
    println!(
        "elements {} nodes {} h_c {:.3e} dt {:.3e} steps {} wall {:.2} s completed {}",
        res.elements,
        res.nodes,
        res.h_contact_m,
        res.dt_s,
        res.steps,
        res.wall_time_s,
        res.completed
    );
    println!(
        "eps {:.5} tc {:.4e} (hertz {:.4e}) Fmax {:.2} (hertz {:.2}) dmax {:.4e} (hertz {:.4e})",
        res.restitution,
        res.contact_time_s,
        h.contact_time(v),
        res.max_force_n,
        h.max_force(v),
        res.max_overlap_m,
        h.max_overlap(v)
    );
    println!("{:#?}", res.energy);
}
