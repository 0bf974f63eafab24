//! Built-in bearing catalog.

use super::Geometry;

/// One catalog entry.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CatalogEntry {
    /// Lower-case key used on the command line (`sr25w`).
    pub key: &'static str,
    /// Maker and model as printed on the part.
    pub name: &'static str,
    /// Geometry of one ball circuit.
    pub geometry: Geometry,
    /// Where the numbers come from; "estimated" entries are not maker data.
    pub provenance: &'static str,
    /// True when any number is an estimate rather than measured or maker data.
    pub estimated: bool,
}

/// The built-in catalog.
pub const CATALOG: &[CatalogEntry] = &[CatalogEntry {
    key: "sr25w",
    name: "THK SR25W",
    geometry: Geometry {
        ball_diameter_mm: 4.0,
        free_space_mm: 2.0,
        balls_in_race: 36,
    },
    provenance: "thesis §1 and §3.1 (d = 4 mm, d_ext = 2 mm, N_B = 36)",
    estimated: false,
}];

/// Finds a catalog entry by key, ignoring case and the characters ` -_`.
pub fn lookup(key: &str) -> Option<&'static CatalogEntry> {
    let norm: String = key
        .chars()
        .filter(|c| !matches!(c, ' ' | '-' | '_'))
        .flat_map(char::to_lowercase)
        .collect();
    CATALOG.iter().find(|e| e.key == norm)
}

/// [`lookup`], or an error naming the key and listing the catalog.
///
/// # Errors
/// [`crate::Error::InvalidSetting`] naming `bearing`.
pub fn find(key: &str) -> crate::Result<&'static CatalogEntry> {
    lookup(key).ok_or_else(|| {
        let keys: Vec<_> = CATALOG.iter().map(|e| e.key).collect();
        crate::Error::setting(
            "bearing",
            format!(
                "unknown bearing '{}' (catalog: {})",
                crate::error::excerpt(key),
                keys.join(", ")
            ),
        )
    })
}
