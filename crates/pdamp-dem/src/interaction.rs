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

    /// Uses `model` for contacts between materials `a` and `b` (both orders).
    pub fn set(&mut self, a: u16, b: u16, mut model: ContactModel) {
        model.prepare();
        let k = self.models.len() as u16;
        self.models.push(model);
        let (a, b) = (a as usize, b as usize);
        self.model_of[a * self.n + b] = k;
        self.model_of[b * self.n + a] = k;
        self.update_fast();
    }

    /// Contact model and elastic constants of the pair (`a`, `b`).
    #[inline]
    pub fn get(&self, a: u16, b: u16) -> (&ContactModel, &PairElastic) {
        let k = a as usize * self.n + b as usize;
        (&self.models[self.model_of[k] as usize], &self.elastic[k])
    }

    /// All distinct models in use.
    pub fn models(&self) -> &[ContactModel] {
        &self.models
    }
}
