//! sRGB and linear light: 8-bit sRGB values to linear light and back (the IEC 61966-2-1
//! curve), through tables computed once.

use std::sync::OnceLock;

/// Entries of the linear-to-sRGB table.
const ENCODE_STEPS: usize = 1 << 14;

/// 8-bit sRGB to linear light (the IEC 61966-2-1 curve), a table computed once.
pub(super) fn srgb_to_linear() -> &'static [f32; 256] {
    static TABLE: OnceLock<[f32; 256]> = OnceLock::new();
    TABLE.get_or_init(|| {
        std::array::from_fn(|i| {
            let c = i as f64 / 255.0;
            let l = if c <= 0.04045 {
                c / 12.92
            } else {
                ((c + 0.055) / 1.055).powf(2.4)
            };
            l as f32
        })
    })
}

/// Linear light in [0, 1] (sampled at [`ENCODE_STEPS`] points) to 8-bit sRGB, a table
/// computed once.
pub(super) fn linear_to_srgb() -> &'static [u8] {
    static TABLE: OnceLock<Vec<u8>> = OnceLock::new();
    TABLE.get_or_init(|| {
        (0..ENCODE_STEPS)
            .map(|i| {
                let l = i as f64 / (ENCODE_STEPS - 1) as f64;
                let c = if l <= 0.003_130_8 {
                    12.92 * l
                } else {
                    1.055 * l.powf(1.0 / 2.4) - 0.055
                };
                (c * 255.0).round().clamp(0.0, 255.0) as u8
            })
            .collect()
    })
}

/// One linear value to 8-bit sRGB through `table` ([`linear_to_srgb`]); values above 1
/// clamp to 255, below 0 (or NaN) to 0.
#[inline(always)]
pub(super) fn encode_one(table: &[u8], l: f32) -> u8 {
    let i = (l * (ENCODE_STEPS - 1) as f32 + 0.5).clamp(0.0, (ENCODE_STEPS - 1) as f32);
    table[i as usize]
}
