//! Virtual elastic materials of the finite-element models.

/// How a 2-D model treats the third dimension.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum PlaneModel {
    /// Thin sheet (σ_zz = 0); stays finite as ν → 0.5.
    #[default]
    Stress,
    /// Infinitely thick body (ε_zz = 0).
    Strain,
}

/// Isotropic linear elastic material.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Material {
    /// Young's modulus E (Pa).
    pub young: f64,
    /// Poisson's ratio ν, in (-1, 0.5).
    pub poisson: f64,
    /// Density ρ (kg/m³).
    pub density: f64,
}

impl Material {
    /// Natural rubber, the seed's virtual material: E = 0.05 GPa, ν = 0.49, ρ = 930 kg/m³.
    pub const RUBBER: Material = Material { young: 5.0e7, poisson: 0.49, density: 930.0 };
}

impl Default for Material {
    fn default() -> Self {
        Material::RUBBER
    }
}
