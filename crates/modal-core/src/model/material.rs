//! Virtual elastic materials of the finite-element models.

use crate::error::{ModalError, OptionError};

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
    /// Natural rubber, the papers' virtual elastic material: E = 0.05 GPa, ν = 0.49, ρ = 930 kg/m³.
    pub const RUBBER: Material = Material {
        young: 5.0e7,
        poisson: 0.49,
        density: 930.0,
    };
    /// Structural steel: E = 200 GPa, ν = 0.30, ρ = 7850 kg/m³.
    pub const STEEL: Material = Material {
        young: 2.0e11,
        poisson: 0.30,
        density: 7850.0,
    };
    /// Aluminium alloy: E = 69 GPa, ν = 0.33, ρ = 2700 kg/m³.
    pub const ALUMINIUM: Material = Material {
        young: 6.9e10,
        poisson: 0.33,
        density: 2700.0,
    };
    /// Cork, a near-zero Poisson's ratio material: E = 0.03 GPa, ν = 0.0, ρ = 240 kg/m³.
    pub const CORK: Material = Material {
        young: 3.0e7,
        poisson: 0.0,
        density: 240.0,
    };
    /// Dimensionless unit material E = 1, ν = 0.3, ρ = 1 (the golden values of
    /// tests/fem_golden.rs).
    pub const UNIT: Material = Material {
        young: 1.0,
        poisson: 0.3,
        density: 1.0,
    };

    /// Names accepted by [`Material::preset`].
    pub const PRESETS: [&'static str; 5] = ["rubber", "steel", "aluminium", "cork", "unit"];

    /// Builds a validated material.
    pub fn new(young: f64, poisson: f64, density: f64) -> Result<Self, ModalError> {
        let m = Material {
            young,
            poisson,
            density,
        };
        m.validate()?;
        Ok(m)
    }

    /// A named preset (case-insensitive; "aluminum" is accepted too).
    pub fn preset(name: &str) -> Result<Self, ModalError> {
        match name.to_ascii_lowercase().as_str() {
            "rubber" => Ok(Self::RUBBER),
            "steel" => Ok(Self::STEEL),
            "aluminium" | "aluminum" => Ok(Self::ALUMINIUM),
            "cork" => Ok(Self::CORK),
            "unit" => Ok(Self::UNIT),
            _ => Err(OptionError::new(
                "material",
                name,
                format!("a known preset ({})", Self::PRESETS.join(", ")),
            )
            .into()),
        }
    }

    /// Checks E > 0, ρ > 0 (both finite) and ν in the open interval (-1, 0.5).
    pub fn validate(&self) -> Result<(), ModalError> {
        if !(self.young.is_finite() && self.young > 0.0) {
            return Err(
                OptionError::new("young", self.young, "Young's modulus, finite and > 0").into(),
            );
        }
        if !(self.density.is_finite() && self.density > 0.0) {
            return Err(OptionError::new("density", self.density, "finite and > 0").into());
        }
        if !(self.poisson > -1.0 && self.poisson < 0.5) {
            return Err(
                OptionError::new("poisson", self.poisson, "Poisson's ratio in (-1, 0.5)").into(),
            );
        }
        Ok(())
    }

    /// Shear modulus μ = E / (2(1+ν)).
    pub fn shear_modulus(&self) -> f64 {
        self.young / (2.0 * (1.0 + self.poisson))
    }

    /// Lamé constants (λ, μ) of a `dim`-dimensional model (docs/method.md §2.4): the 3-D values for
    /// `dim == 3`; in 2-D, plane stress uses the reduced λ* = Eν/(1−ν²).
    pub fn lame(&self, dim: usize, plane: PlaneModel) -> (f64, f64) {
        let (e, nu) = (self.young, self.poisson);
        let mu = self.shear_modulus();
        let lambda = if dim == 2 && plane == PlaneModel::Stress {
            e * nu / (1.0 - nu * nu)
        } else {
            e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))
        };
        (lambda, mu)
    }
}

impl Default for Material {
    fn default() -> Self {
        Material::RUBBER
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_validate_and_bad_values_fail() {
        for name in Material::PRESETS {
            Material::preset(name).unwrap().validate().unwrap();
        }
        assert!(Material::preset("jelly").is_err());
        assert!(Material::new(1.0, 0.5, 1.0).is_err());
        assert!(Material::new(1.0, -1.0, 1.0).is_err());
        assert!(Material::new(0.0, 0.3, 1.0).is_err());
        assert!(Material::new(1.0, 0.3, -2.0).is_err());
        assert!(Material::new(f64::NAN, 0.3, 1.0).is_err());
        assert!(Material::new(1.0, f64::NAN, 1.0).is_err());
    }

    #[test]
    fn plane_stress_lame_matches_voigt_constants() {
        let m = Material::UNIT;
        let (l, mu) = m.lame(2, PlaneModel::Stress);
        let c = 1.0 / (1.0 - 0.09);
        assert!((l + 2.0 * mu - c).abs() < 1e-15);
        assert!((l - 0.3 * c).abs() < 1e-15);
        let (l3, _) = m.lame(3, PlaneModel::Stress);
        assert!((l3 - 0.3 / (1.3 * 0.4)).abs() < 1e-15);
        assert_eq!(m.lame(2, PlaneModel::Strain).0, l3);
    }
}
