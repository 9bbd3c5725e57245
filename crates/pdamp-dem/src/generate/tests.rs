use super::*;
use crate::math::Vec3;
use std::f64::consts::PI;
use std::time::Instant;

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

fn quantile_sorted(v: &[f64], p: f64) -> f64 {
    let x = p * (v.len() - 1) as f64;
    let i = x.floor() as usize;
    let f = x - i as f64;
    if i + 1 < v.len() {
        v[i] * (1.0 - f) + v[i + 1] * f
    } else {
        v[i]
    }
}

fn no_overlaps(pos: &[Vec3], radii: &[f64], gap: f64) {
    let r_max = radii.iter().cloned().fold(0.0, f64::max);
    let (mut lo, mut hi) = (pos[0], pos[0]);
    for p in pos {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    let mut grid = CellGrid::new(lo, hi, 2.0 * r_max + gap, pos.len());
    // Reuse the grid with inflated radii: overlap iff d < r_i + r_j + gap (tolerance 1e-12).
    let inflated: Vec<f64> = radii.iter().map(|r| r + 0.5 * gap - 1e-12).collect();
    for (i, p) in pos.iter().enumerate() {
        assert!(
            !grid.overlaps(p, inflated[i], &pos[..i], &inflated[..i]),
            "particle {i} overlaps"
        );
        grid.insert(i as u32, p);
    }
}

fn all_inside(region: &Region, pos: &[Vec3], radii: &[f64]) {
    for (i, (p, r)) in pos.iter().zip(radii).enumerate() {
        assert!(
            region.contains_sphere(p, r - 1e-12),
            "particle {i} at {p:?} outside"
        );
    }
}

#[test]
fn normal_cdf_and_quantile() {
    assert!((normal_cdf(0.0) - 0.5).abs() < 1e-15);
    assert!((normal_cdf(1.0) - 0.841_344_746_068_542_9).abs() < 1e-14);
    assert!((normal_cdf(-3.5) / 2.326_290_790_355_250_4e-4 - 1.0).abs() < 1e-12);
    assert!((normal_cdf(-5.0) / 2.866_515_718_791_939e-7 - 1.0).abs() < 1e-10);
    assert!((normal_quantile(0.9) - 1.281_551_565_544_600_5).abs() < 1e-12);
    assert!((normal_quantile(0.025) + 1.959_963_984_540_054).abs() < 1e-12);
    for &p in &[1e-10, 1e-4, 0.01, 0.3, 0.5, 0.77, 0.99, 1.0 - 1e-6] {
        assert!(
            (normal_cdf(normal_quantile(p)) / p - 1.0).abs() < 1e-10,
            "p = {p}"
        );
    }
}

#[test]
fn lognormal_reproduces_median_and_sigma() {
    let d = SizeDistribution::LogNormal {
        median_diameter_m: 1.0e-3,
        sigma: 0.2707,
        min_radius_m: None,
        max_radius_m: None,
    };
    d.validate().unwrap();
    let mut r = d.sample_n(20_000, 42);
    let med_d = 2.0 * median(&mut r);
    assert!((med_d / 1.0e-3 - 1.0).abs() < 0.02, "median {med_d}");
    let ln: Vec<f64> = r.iter().map(|r| (2.0 * r).ln()).collect();
    let mean = ln.iter().sum::<f64>() / ln.len() as f64;
    let std = (ln.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (ln.len() - 1) as f64).sqrt();
    assert!((std / 0.2707 - 1.0).abs() < 0.03, "sigma {std}");
    // Mean volume: closed form vs. sample mean.
    let vs = r.iter().map(|r| 4.0 / 3.0 * PI * r.powi(3)).sum::<f64>() / r.len() as f64;
    assert!((vs / d.mean_volume_m3() - 1.0).abs() < 0.02);
    assert_eq!(d.max_radius_m(), f64::INFINITY);
}

#[test]
fn lognormal_table_a2_cutoffs() {
    let d = SizeDistribution::paper_table_a2();
    d.validate().unwrap();
    let (lo, hi) = (0.353414e-3, 0.707385e-3);
    assert_eq!((d.min_radius_m(), d.max_radius_m()), (lo, hi));
    let r = d.sample_n(20_000, 7);
    assert!(r.iter().all(|&x| (lo..=hi).contains(&x)));
    // Truncated moments: closed form vs. sampling.
    let mean = r.iter().sum::<f64>() / r.len() as f64;
    assert!(
        (mean / d.mean_radius_m() - 1.0).abs() < 0.005,
        "{mean} vs {}",
        d.mean_radius_m()
    );
    let vs = r.iter().map(|r| 4.0 / 3.0 * PI * r.powi(3)).sum::<f64>() / r.len() as f64;
    assert!((vs / d.mean_volume_m3() - 1.0).abs() < 0.01);
    // The cut-offs are D10 and D90 of the untruncated distribution: 80 % mass kept, and the
    // truncated median equals the untruncated one.
    assert!((d.quantile_radius_m(0.5) / 0.5e-3 - 1.0).abs() < 1e-6);
    assert!(
        (d.quantile_radius_m(0.0) - lo).abs() < 1e-12
            && (d.quantile_radius_m(1.0) - hi).abs() < 1e-12
    );
    // Deterministic.
    assert_eq!(r, d.sample_n(20_000, 7));
    assert_ne!(r, d.sample_n(20_000, 8));
}

#[test]
fn lognormal_paper_original_d10_d90() {
    let d50 = 26.5646e-6;
    let d = SizeDistribution::LogNormal {
        median_diameter_m: d50,
        sigma: 0.2707,
        min_radius_m: None,
        max_radius_m: None,
    };
    // Analytic, as in the brief: exp(ln D50 ± 1.2816 σ).
    let d10 = (d50.ln() - 1.2816 * 0.2707).exp();
    let d90 = (d50.ln() + 1.2816 * 0.2707).exp();
    assert!((d10 / 18.7766e-6 - 1.0).abs() < 0.02, "D10 {d10}");
    assert!((d90 / 37.5828e-6 - 1.0).abs() < 0.02, "D90 {d90}");
    // Quantile function.
    assert!((2.0 * d.quantile_radius_m(0.1) / 18.7766e-6 - 1.0).abs() < 0.002);
    assert!((2.0 * d.quantile_radius_m(0.9) / 37.5828e-6 - 1.0).abs() < 0.002);
    // Sampling.
    let mut r = d.sample_n(20_000, 3);
    r.sort_by(f64::total_cmp);
    let (s10, s90) = (
        2.0 * quantile_sorted(&r, 0.1),
        2.0 * quantile_sorted(&r, 0.9),
    );
    assert!((s10 / 18.7766e-6 - 1.0).abs() < 0.02, "sampled D10 {s10}");
    assert!((s90 / 37.5828e-6 - 1.0).abs() < 0.02, "sampled D90 {s90}");
}

#[test]
fn uniform_and_monodisperse() {
    let d = SizeDistribution::Uniform {
        min_radius_m: 1e-3,
        max_radius_m: 2e-3,
    };
    d.validate().unwrap();
    let r = d.sample_n(20_000, 1);
    assert!(r.iter().all(|&x| (1e-3..=2e-3).contains(&x)));
    let mean = r.iter().sum::<f64>() / r.len() as f64;
    assert!((mean / 1.5e-3 - 1.0).abs() < 0.005);
    assert!((d.mean_radius_m() - 1.5e-3).abs() < 1e-15);
    let v_exact = 4.0 / 3.0 * PI * (2e-3f64.powi(4) - 1e-3f64.powi(4)) / (4.0 * 1e-3);
    assert!((d.mean_volume_m3() / v_exact - 1.0).abs() < 1e-12);
    let m = SizeDistribution::Monodisperse { radius_m: 5e-4 };
    assert_eq!(m.sample_n(3, 0), vec![5e-4; 3]);
    assert!((m.mean_volume_m3() - 4.0 / 3.0 * PI * 1.25e-10).abs() < 1e-20);
}

#[test]
fn validation_messages_name_fields() {
    let e = SizeDistribution::Uniform {
        min_radius_m: 2.0,
        max_radius_m: 1.0,
    }
    .validate()
    .unwrap_err();
    assert_eq!(e.key(), "min_radius_m", "{e}");
    let e = SizeDistribution::Monodisperse { radius_m: -1.0 }
        .validate()
        .unwrap_err();
    assert_eq!(e.key(), "radius_m", "{e}");
    let e = SizeDistribution::LogNormal {
        median_diameter_m: 1e-3,
        sigma: -0.1,
        min_radius_m: None,
        max_radius_m: None,
    }
    .validate()
    .unwrap_err();
    assert_eq!(e.key(), "sigma", "{e}");
    let narrow = SizeDistribution::LogNormal {
        median_diameter_m: 1e-3,
        sigma: 0.1,
        min_radius_m: Some(1.0e-3),
        max_radius_m: Some(1.1e-3),
    };
    assert!(
        narrow
            .validate()
            .unwrap_err()
            .to_string()
            .contains("probability mass")
    );
    let e = Region::Cylinder {
        base_center_m: Vec3::zeros(),
        axis: Vec3::zeros(),
        radius_m: 1.0,
        length_m: 1.0,
    }
    .validate()
    .unwrap_err();
    assert_eq!(e.key(), "axis", "{e}");
}

#[test]
fn narrow_truncation_terminates_and_stays_inside() {
    // Window far in the tail (mass ≈ 3e-5): the inverse-CDF fallback keeps samples inside.
    let d = SizeDistribution::LogNormal {
        median_diameter_m: 1e-3,
        sigma: 0.2,
        min_radius_m: Some(1.0e-3),
        max_radius_m: Some(1.2e-3),
    };
    d.validate().unwrap();
    let r = d.sample_n(2000, 5);
    assert!(r.iter().all(|&x| (1.0e-3..=1.2e-3).contains(&x)));
}

#[test]
fn region_containment_and_volume() {
    let b = Region::Box {
        min_m: Vec3::zeros(),
        max_m: Vec3::new(1.0, 2.0, 3.0),
    };
    assert!((b.volume_m3() - 6.0).abs() < 1e-15);
    assert!(b.contains_sphere(&Vec3::new(0.5, 0.5, 0.5), 0.5));
    assert!(!b.contains_sphere(&Vec3::new(0.5, 0.5, 0.5), 0.50001));
    let c = Region::Cylinder {
        base_center_m: Vec3::new(1.0, 0.0, 0.0),
        axis: Vec3::new(2.0, 0.0, 0.0),
        radius_m: 1.0,
        length_m: 4.0,
    };
    assert!((c.volume_m3() - 4.0 * PI).abs() < 1e-12);
    assert!(c.contains_sphere(&Vec3::new(3.0, 0.5, 0.0), 0.5));
    assert!(!c.contains_sphere(&Vec3::new(3.0, 0.5, 0.1), 0.5));
    assert!(!c.contains_sphere(&Vec3::new(1.4, 0.0, 0.0), 0.5));
    let (lo, hi) = c.bounding_box();
    assert!(
        (lo - Vec3::new(1.0, -1.0, -1.0)).norm() < 1e-12
            && (hi - Vec3::new(5.0, 1.0, 1.0)).norm() < 1e-12
    );
}

#[test]
fn grid_packing_fills_from_bottom() {
    let region = Region::Box {
        min_m: Vec3::zeros(),
        max_m: Vec3::new(0.01, 0.01, 0.02),
    };
    let radii = SizeDistribution::paper_table_a2().sample_n(500, 1);
    let up = Vec3::z();
    let pos = grid_packing(&region, &radii, 1e-5, &up).unwrap();
    assert_eq!(pos.len(), 500);
    no_overlaps(&pos, &radii, 1e-5);
    all_inside(&region, &pos, &radii);
    // Layer by layer: heights never decrease.
    assert!(pos.windows(2).all(|w| w[1].z >= w[0].z - 1e-12));
    // Error states how many fit.
    let many = vec![0.5e-3; 100_000];
    let e = grid_packing(&region, &many, 0.0, &up).unwrap_err();
    assert!(e.to_string().contains("holds only 2000 of 100000"), "{e}");
    assert!(
        matches!(
            e,
            PackingError::RegionTooSmall {
                fitted: 2000,
                requested: 100_000,
                ..
            }
        ),
        "{e:?}"
    );
    // Gravity along −x: bottom is the x = 0 face.
    let pos = grid_packing(&region, &radii, 1e-5, &Vec3::x()).unwrap();
    assert!(pos.windows(2).all(|w| w[1].x >= w[0].x - 1e-12));
    all_inside(&region, &pos, &radii);
}

#[test]
fn tight_packing_box_and_cylinder() {
    let d = 1.0e-3;
    let region = Region::Box {
        min_m: Vec3::zeros(),
        max_m: Vec3::repeat(20.0 * d),
    };
    let sites = lattice_sites(&region, d, 0.5 * d, &Vec3::z(), Lattice::Hcp).unwrap();
    let radii = vec![0.5 * d; sites.len()];
    let pos = tight_packing(&region, &radii, 0.0, &Vec3::z()).unwrap();
    assert_eq!(pos, sites);
    no_overlaps(&pos, &radii, 0.0);
    all_inside(&region, &pos, &radii);
    let phi = pos.len() as f64 * PI / 6.0 * d.powi(3) / region.volume_m3();
    println!(
        "HCP in 20^3 d box: {} spheres, solid fraction {phi:.4}",
        pos.len()
    );
    assert!(phi > 0.6, "solid fraction {phi}");
    let fcc = lattice_sites(&region, d, 0.5 * d, &Vec3::z(), Lattice::Fcc).unwrap();
    no_overlaps(&fcc, &radii[..fcc.len().min(radii.len())], 0.0);
    let cubic = lattice_sites(&region, d, 0.5 * d, &Vec3::z(), Lattice::SimpleCubic).unwrap();
    assert_eq!(cubic.len(), 8000);
    // Nearest-neighbour distance is exactly d in the bulk.
    let mut min_d = f64::INFINITY;
    for i in 0..200 {
        for j in 0..pos.len() {
            if i != j {
                min_d = min_d.min((pos[i] - pos[j]).norm());
            }
        }
    }
    assert!((min_d / d - 1.0).abs() < 1e-9);

    // Cylinder along y (gravity −y), polydisperse, with gap.
    let cyl = Region::Cylinder {
        base_center_m: Vec3::new(0.0, -0.01, 0.0),
        axis: Vec3::y(),
        radius_m: 0.008,
        length_m: 0.03,
    };
    let radii = SizeDistribution::paper_table_a2().sample_n(2000, 9);
    let pos = tight_packing(&cyl, &radii, 2e-5, &Vec3::y()).unwrap();
    no_overlaps(&pos, &radii, 2e-5);
    all_inside(&cyl, &pos, &radii);
    assert!(pos.windows(2).all(|w| w[1].y >= w[0].y - 1e-12));
    // Top partial layer is centred on the axis.
    let top_y = pos.last().unwrap().y;
    let top: Vec<&Vec3> = pos.iter().filter(|p| (p.y - top_y).abs() < 1e-9).collect();
    let cx = top.iter().map(|p| p.x).sum::<f64>() / top.len() as f64;
    let cz = top.iter().map(|p| p.z).sum::<f64>() / top.len() as f64;
    assert!(cx.hypot(cz) < 0.003, "top layer centre ({cx}, {cz})");
}

#[test]
fn random_insertion_no_overlap_and_deterministic() {
    let region = Region::Cylinder {
        base_center_m: Vec3::zeros(),
        axis: Vec3::z(),
        radius_m: 0.01,
        length_m: 0.02,
    };
    let radii = SizeDistribution::paper_table_a2().sample_n(2000, 2);
    let a = random_insertion(&region, &radii, 11, 1000, None).unwrap();
    no_overlaps(&a, &radii, 0.0);
    all_inside(&region, &a, &radii);
    let b = random_insertion(&region, &radii, 11, 1000, None).unwrap();
    assert_eq!(a, b);
    let c = random_insertion(&region, &radii, 12, 1000, None).unwrap();
    assert_ne!(a, c);
    // Too many particles: error names how many were placed.
    let many = vec![0.7e-3; 20_000];
    let e = random_insertion(&region, &many, 1, 50, None).unwrap_err();
    let msg = e.to_string();
    assert!(
        msg.contains("placed only") && msg.contains("of 20000"),
        "{e}"
    );
    assert!(
        matches!(
            e,
            PackingError::NoFreePosition {
                requested: 20000,
                ..
            }
        ),
        "{e:?}"
    );
}

#[test]
fn random_insertion_30000_fast() {
    let region = Region::Box {
        min_m: Vec3::zeros(),
        max_m: Vec3::repeat(0.038),
    };
    let radii = SizeDistribution::paper_table_a2().sample_n(30_000, 4);
    let phi = radii
        .iter()
        .map(|r| 4.0 / 3.0 * PI * r.powi(3))
        .sum::<f64>()
        / region.volume_m3();
    let t = Instant::now();
    let pos = random_insertion(&region, &radii, 5, 1000, None).unwrap();
    let dt = t.elapsed().as_secs_f64();
    println!("random insertion: 30000 particles, solid fraction {phi:.3}, {dt:.3} s");
    no_overlaps(&pos, &radii, 0.0);
    all_inside(&region, &pos, &radii);
    assert!(dt < 5.0, "{dt} s");
}

#[test]
fn random_insertion_layered() {
    let region = Region::Box {
        min_m: Vec3::zeros(),
        max_m: Vec3::new(0.01, 0.01, 0.03),
    };
    let radii = SizeDistribution::paper_table_a2().sample_n(800, 6);
    let layering = Layering {
        up: Vec3::z(),
        layer_height_m: 2e-3,
    };
    let t = Instant::now();
    let pos = random_insertion(&region, &radii, 3, 200, Some(&layering)).unwrap();
    println!(
        "layered insertion of 800: {:.3} s, top z {:.4}",
        t.elapsed().as_secs_f64(),
        pos.iter().map(|p| p.z).fold(0.0, f64::max)
    );
    no_overlaps(&pos, &radii, 0.0);
    all_inside(&region, &pos, &radii);
    // Layer index (by centre height) never decreases along the insertion order.
    let layer = |p: &Vec3| (p.z / 2e-3).floor() as i64;
    assert!(pos.windows(2).all(|w| layer(&w[1]) >= layer(&w[0])));
    // The bottom is filled first: the upper part of the box stays empty.
    assert!(pos.iter().all(|p| p.z < 0.025));
    assert_eq!(
        pos,
        random_insertion(&region, &radii, 3, 200, Some(&layering)).unwrap()
    );
}
