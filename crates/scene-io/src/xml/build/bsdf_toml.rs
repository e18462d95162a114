//! How TOML spells a BSDF type: the data a row of `BSDFS` carries for the TOML reader. TOML's
//! `tree/material.rs` turns each group of keys below into the tree's parameters, so a new material
//! made of these groups needs no code there; a key TOML has never had is a new group (and a field
//! of `schema.rs`).

/// One TOML material type and the tree it becomes.
pub(crate) struct TomlType {
    /// Its `type` in a TOML `[materials.NAME]` table.
    pub name: &'static str,
    /// String parameters it always adds (TOML's `mirror` is a `conductor` of material `none`).
    pub fixed: &'static [(&'static str, &'static str)],
    /// The groups of keys it takes, in the order their parameters go into the tree.
    pub keys: &'static [Keys],
    /// Inside `twosided` whatever the file says (lt's diffuse, mirror and glossy reflect on both
    /// sides); the others are when they take `Keys::Twosided` and it is true.
    pub always_twosided: bool,
}

/// A group of TOML keys and the tree parameters they become (TOML name → tree name).
#[derive(Clone, Copy)]
pub(crate) enum Keys {
    /// `albedo` or `albedo_texture` → `to` (a reflectance), required or not.
    Albedo { to: &'static str, required: bool },
    /// `reflectance` → `specular_reflectance`, with `textured` also `reflectance_texture`.
    Reflectance { textured: bool },
    /// `transmittance` → `specular_transmittance`.
    Transmittance,
    /// `ior` (required) → `int_ior` over `ext_ior` = 1.
    DielectricIor,
    /// `ior` → `int_ior` over `ext_ior` = 1, polypropylene in air when absent; `rough`: ≠ 1.
    PlasticIor { rough: bool },
    /// `roughness` (required) → a GGX `alpha`.
    Roughness,
    /// `distribution` and `alpha`; `anisotropic` adds `alpha_u`, `alpha_v` and their textures
    /// and `alpha_texture`.
    Microfacet { anisotropic: bool },
    /// `material` (Mitsuba's name of a complex IOR), or `eta` and `k`.
    ComplexIor,
    /// `nonlinear`.
    Nonlinear,
    /// `twosided`: `twosided` around the BSDF when true.
    Twosided,
    /// Mitsuba's principled keys with `ior` → `eta`; `thin` for `principledthin`'s set.
    Principled { thin: bool },
}

impl Keys {
    /// The TOML keys of the group.
    pub(crate) fn toml_keys(self) -> &'static [&'static str] {
        match self {
            Keys::Albedo { .. } => &["albedo", "albedo_texture"],
            Keys::Reflectance { textured: false } => &["reflectance"],
            Keys::Reflectance { textured: true } => &["reflectance", "reflectance_texture"],
            Keys::Transmittance => &["transmittance"],
            Keys::DielectricIor | Keys::PlasticIor { .. } => &["ior"],
            Keys::Roughness => &["roughness"],
            Keys::Microfacet { anisotropic: false } => &["distribution", "alpha"],
            Keys::Microfacet { anisotropic: true } => &[
                "distribution",
                "alpha",
                "alpha_texture",
                "alpha_u",
                "alpha_v",
                "alpha_u_texture",
                "alpha_v_texture",
            ],
            Keys::ComplexIor => &["material", "eta", "k"],
            Keys::Nonlinear => &["nonlinear"],
            Keys::Twosided => &["twosided"],
            Keys::Principled { thin: false } => &[
                "base_color",
                "base_color_texture",
                "roughness",
                "anisotropic",
                "spec_trans",
                "spec_tint",
                "sheen",
                "sheen_tint",
                "flatness",
                "ior",
                "metallic",
                "clearcoat",
                "clearcoat_gloss",
                "specular",
            ],
            Keys::Principled { thin: true } => &[
                "base_color",
                "base_color_texture",
                "roughness",
                "anisotropic",
                "spec_trans",
                "spec_tint",
                "sheen",
                "sheen_tint",
                "flatness",
                "ior",
                "diff_trans",
            ],
        }
    }
}

/// A BSDF type TOML writes under its own name, with nothing fixed and no forced back side.
pub(super) const fn same_name(name: &'static str, keys: &'static [Keys]) -> TomlType {
    TomlType {
        name,
        fixed: &[],
        keys,
        always_twosided: false,
    }
}
