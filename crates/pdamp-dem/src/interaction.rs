//! The table of contact models per pair of materials, with the effective elastic constants of
//! each pair precomputed ([D Eq. 2.71]; Mindlin's shear modulus).

use crate::contact::ContactModel;
use crate::material::{Material, effective_modulus, effective_shear_modulus};

/// Constant elastic properties of a material pair.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PairElastic {
    /// Effective Young's modulus $\bar E$, Pa.
    pub e_eff_pa: f64,
    /// Effective shear modulus $\bar G$, Pa.
    pub g_eff_pa: f64,
    /// Mean Poisson's ratio.
    pub poisson_mean: f64,
}

/// Contact model and elastic constants for every ordered pair of materials (symmetric).
#[derive(Debug, Clone)]
pub struct InteractionTable {
    n: usize,
    models: Vec<ContactModel>,
    model_of: Vec<u16>,
    elastic: Vec<PairElastic>,
    /// Constants of the one-pass Hertz–Mindlin kernel for pairs whose model is LIGGGHTS'
    /// `hertz` + `tangential history` without rolling resistance or adhesion.
    hm_fast: Vec<Option<HmConstants>>,
    /// The constants shared by every pair, if all pairs use the one-pass law with the same ones.
    hm_uniform: Option<HmConstants>,
}

/// Constants of a pair with the one-pass Hertz–Mindlin law (see
/// [`ContactModel::hertz_mindlin_constants`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct HmConstants {
    /// Effective Young's modulus $\bar E$, Pa.
    pub e_eff_pa: f64,
    /// Effective shear modulus $\bar G$, Pa.
    pub g_eff_pa: f64,
    /// $-2\sqrt{5/6}\,\beta(e)$ of LIGGGHTS' damping coefficients.
    pub damping: f64,
    /// Coulomb friction coefficient.
    pub mu: f64,
    /// Clip the normal force at zero (no attraction).
    pub clip_attractive: bool,
}

impl InteractionTable {
    /// Every pair of `materials` uses `default_model`.
    pub fn new(materials: &[Material], default_model: ContactModel) -> Self {
        let n = materials.len();
        let mut elastic = Vec::with_capacity(n * n);
        for a in materials {
            for b in materials {
                elastic.push(PairElastic {
                    e_eff_pa: effective_modulus(a, b),
                    g_eff_pa: effective_shear_modulus(a, b),
                    poisson_mean: 0.5 * (a.poisson_ratio + b.poisson_ratio),
                });
            }
        }
        let mut m = default_model;
        m.prepare();
        let mut t = Self {
            n,
            models: vec![m],
            model_of: vec![0; n * n],
            elastic,
            hm_fast: Vec::new(),
            hm_uniform: None,
        };
        t.update_fast();
        t
    }

    fn update_fast(&mut self) {
        self.hm_fast = (0..self.n * self.n)
            .map(|k| {
                let m = &self.models[self.model_of[k] as usize];
                let el = &self.elastic[k];
                m.hertz_mindlin_constants()
                    .map(|(damping, mu, clip_attractive)| HmConstants {
                        e_eff_pa: el.e_eff_pa,
                        g_eff_pa: el.g_eff_pa,
                        damping,
                        mu,
                        clip_attractive,
                    })
            })
            .collect();
        self.hm_uniform = match self.hm_fast.first() {
            Some(Some(c)) if self.hm_fast.iter().all(|x| x.as_ref() == Some(c)) => Some(*c),
            _ => None,
        };
    }

    /// The one-pass Hertz–Mindlin constants if every pair of materials uses them.
    #[inline]
    pub(crate) fn hm_uniform(&self) -> Option<&HmConstants> {
        self.hm_uniform.as_ref()
    }

    /// Constants of the one-pass Hertz–Mindlin kernel for the pair (`a`, `b`), if its model
    /// is that law.
    #[inline]
    pub(crate) fn hm_fast(&self, a: u16, b: u16) -> Option<&HmConstants> {
        self.hm_fast[a as usize * self.n + b as usize].as_ref()
    }

    /// Number of materials.
    pub fn num_materials(&self) -> usize {
        self.n
    }

    /// Uses `model` for contacts between materials `a` and `b` (both orders). The table keeps
    /// only the models some pair uses, each once: an identical model is shared, and a model no
    /// pair uses any more is dropped (the neighbour reach of [`crate::World`] is taken over
    /// [`Self::models`], so a replaced long-range model must not linger there).
    pub fn set(&mut self, a: u16, b: u16, mut model: ContactModel) {
        model.prepare();
        let k = match self.models.iter().position(|m| *m == model) {
            Some(k) => k as u16,
            None => {
                self.models.push(model);
                (self.models.len() - 1) as u16
            }
        };
        let (a, b) = (a as usize, b as usize);
        self.model_of[a * self.n + b] = k;
        self.model_of[b * self.n + a] = k;
        self.drop_unused_models();
        self.update_fast();
    }

    /// Removes the models no pair refers to and renumbers the rest (order kept).
    fn drop_unused_models(&mut self) {
        let mut used = vec![false; self.models.len()];
        for &k in &self.model_of {
            used[k as usize] = true;
        }
        if used.iter().all(|&u| u) {
            return;
        }
        let mut new_index = vec![u16::MAX; self.models.len()];
        let mut kept = Vec::with_capacity(self.models.len());
        for (k, m) in std::mem::take(&mut self.models).into_iter().enumerate() {
            if used[k] {
                new_index[k] = kept.len() as u16;
                kept.push(m);
            }
        }
        self.models = kept;
        for k in &mut self.model_of {
            *k = new_index[*k as usize];
        }
    }

    /// Contact model and elastic constants of the pair (`a`, `b`).
    #[inline]
    pub fn get(&self, a: u16, b: u16) -> (&ContactModel, &PairElastic) {
        let k = a as usize * self.n + b as usize;
        (&self.models[self.model_of[k] as usize], &self.elastic[k])
    }

    /// The distinct models some pair of materials uses, each once.
    pub fn models(&self) -> &[ContactModel] {
        &self.models
    }
}

#[cfg(test)]
mod set_tests {
    use super::*;
    use crate::contact::{ContactModel, DmtAdhesion, FrictionLaw, NormalLaw};

    fn linear(restitution: f64) -> ContactModel {
        ContactModel {
            normal: NormalLaw::Linear {
                stiffness_n_m: 1e5,
                restitution,
                clip_attractive: false,
            },
            friction: FrictionLaw::Frictionless,
            rolling: None,
            adhesion: None,
        }
    }

    /// `set` keeps each model once and drops a model no pair uses: overriding every pair of an
    /// adhesive default leaves no adhesive model, so the neighbour reach of a world built on
    /// the table has no adhesion range left (before, every `set` appended a model and the
    /// replaced default stayed in `models()` and in the reach).
    #[test]
    fn set_keeps_only_models_in_use() {
        let mats = [
            crate::Material::new("a", 7800.0, 2e9, 0.3),
            crate::Material::new("b", 2700.0, 7e10, 0.33),
        ];
        let mut sticky = linear(0.5);
        sticky.adhesion = Some(DmtAdhesion {
            surface_energy_j_m2: 0.0,
            hamaker_constant_j: 4e-19,
            cutoff_ratio: 0.01,
        });
        let mut t = InteractionTable::new(&mats, sticky.clone());
        for _ in 0..1000 {
            t.set(0, 1, linear(0.7));
        }
        assert_eq!(
            t.models().len(),
            2,
            "the default and one override, each once"
        );
        t.set(0, 0, linear(0.7));
        t.set(1, 1, linear(0.7));
        assert_eq!(t.models(), &[linear(0.7)], "the replaced default is gone");
        assert!(t.models().iter().all(|m| m.adhesion.is_none()));
        assert_eq!(t.get(1, 0).0, &linear(0.7));
        // A second law for one pair, then back: still two, then one.
        t.set(1, 1, linear(0.2));
        assert_eq!(t.models().len(), 2);
        assert_eq!(t.get(1, 1).0, &linear(0.2));
        assert_eq!(t.get(0, 1).0, &linear(0.7));
        t.set(1, 1, linear(0.7));
        assert_eq!(t.models().len(), 1);

        // In a world: the reach after the adhesive default is replaced everywhere is 0.
        let mut w = crate::World::new(mats.to_vec(), sticky, 1e-6);
        w.set_contact_model(0, 0, linear(0.7));
        w.set_contact_model(0, 1, linear(0.7));
        w.set_contact_model(1, 1, linear(0.7));
        w.add_particle(crate::Vec3::zeros(), 1e-3, 0);
        w.initialize();
        assert_eq!(w.neighbors.extra_range_m, 0.0);
    }
}
