//! The storage policy: which path a contact set takes (dense, per-active-column, the
//! contact zone's columns or flexibilities, [`ZoneStorage`]), its memory, and the phrase
//! that says which ran; shared by [`Delassus::plan`] (`signorini check`, the memory
//! ledger), [`Delassus::new`] and [`Delassus::condense_zone`] (`zone.rs`, which forms
//! what this file chose).

use super::*;

/// What the contact zone keeps ([`Delassus::condense_zone`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ZoneStorage {
    /// `Y = Â⁻¹S`, `E = Â⁻¹K N S` (`n × z`) and `F`, `F_E` (`z × z`): corrections are
    /// combinations of the columns of `Y` and `E`.
    Full,
    /// `F`, `F_E` only: `n`-space corrections by one sparse solve of `G x`, zone rows by
    /// [`Delassus::zone_corrections`].
    Flexibility,
}

/// Columns of the zone formed per pass by [`ZoneStorage::Flexibility`]'s set-up: a
/// multiple of [`crate::linalg::SOLVE_CHUNK`], so that the factor's block solves see the
/// same chunks as [`ZoneStorage::Full`]'s and give `F`, `F_E` bit for bit, and two
/// chunks so that both threads solve at once.
pub const ZONE_CHUNK: usize = 2 * crate::linalg::SOLVE_CHUNK;

/// The planned Delassus data ([`Delassus::plan`]).
#[derive(Clone, Debug, PartialEq)]
pub struct DelassusPlan {
    /// The phrase [`Delassus::describe`] will give.
    pub describe: String,
    /// Every column formed per linearization (dense, or dense on the contact zone).
    pub dense: bool,
    /// Bytes of the blocks, columns and scratch.
    pub bytes: u64,
    /// The contact zone keeps its flexibilities only ([`ZoneStorage::Flexibility`]).
    pub zone_flexibilities: bool,
    /// Of [`DelassusPlan::bytes`], the set-up's swept chunks (freed after it).
    pub setup_bytes: u64,
}

/// [`DelassusKind::Auto`]'s and the user's choice of the dense path.
pub(super) fn choose_dense(
    kind: DelassusKind,
    n: usize,
    m: usize,
    per: usize,
    g_constant: bool,
) -> bool {
    match kind {
        DelassusKind::Dense => true,
        DelassusKind::Columns => false,
        // a constant G under `flexibility`: the columns, with the matrix-free products
        // through the flexibilities of its dofs (`Delassus::condense_products`)
        DelassusKind::Flexibility if g_constant => false,
        DelassusKind::Auto | DelassusKind::Flexibility => {
            (g_constant || m <= AUTO_DENSE_MAX_CONTACTS)
                && n.saturating_mul(m).saturating_mul(8 * per) <= AUTO_DENSE_MAX_BYTES
        }
    }
}

/// Columns the store holds: all on the dense path, else the caller's pool or as many
/// as fit in the pool budget.
pub(super) fn pool_cap(dense: bool, pool: usize, m: usize, per: usize) -> usize {
    if dense {
        m
    } else if pool > 0 {
        m.min(pool)
    } else {
        m.min((COLUMN_POOL_BYTES / (8 * per * m.max(1))).max(1))
    }
}

/// Bytes of the contact zone's blocks (`Y`, `E`: `n × z`; `F`, `F_E`: `z × z`; `F B`,
/// `F_E B`: `z × m`) and of the `m × m` operators.
pub(super) fn zone_bytes(n: usize, z: usize, m: usize, per: usize) -> usize {
    n.saturating_mul(z)
        .saturating_mul(8 * per)
        .saturating_add(m.saturating_mul(m).saturating_mul(8 * (per + 1)))
        .saturating_add(z.saturating_mul(z + m).saturating_mul(8 * per))
}

/// Bytes of [`ZoneStorage::Flexibility`]'s data: `F`, `F_E`, `F B`, `F_E B`, the `m × m`
/// operators and the two `n`-vectors of its correction solves. The dense budget bounds
/// these; the set-up's scratch ([`flexibility_scratch_bytes`]) is freed after it.
pub(super) fn flexibility_bytes(n: usize, z: usize, m: usize, per: usize) -> usize {
    m.saturating_mul(m)
        .saturating_mul(8 * (per + 1))
        .saturating_add(z.saturating_mul(z + m).saturating_mul(8 * per))
        .saturating_add(n.saturating_mul(16))
}

/// The `n ×` [`ZONE_CHUNK`] blocks (`Y` and, with `W_D`, `E`) of
/// [`ZoneStorage::Flexibility`]'s set-up: freed once the flexibilities are formed, but
/// part of the run's peak, so the ledger counts them.
pub(super) fn flexibility_scratch_bytes(n: usize, z: usize, per: usize) -> usize {
    n.saturating_mul(ZONE_CHUNK.min(z)).saturating_mul(8 * per)
}

/// The zone storage tried first: the flexibilities where the user asks for them, and
/// under [`DelassusKind::Auto`] where the integrator iterates on the zone alone (the
/// θ-method core; Schatzman–Paoli's loop corrects `q` at every iteration and keeps the
/// columns). Measured with `zone_iterates`, flexibilities against `Y`, `E` (medians of
/// two runs, `--no-fields --no-plots`): `hex_bars.toml` 300 steps 6.7 against 9.2 ms per
/// step; two 12³ cubes 33 against 51 ms and 150 against 322 MiB; two 16³ cubes 116
/// against 178 ms and 387 MiB against 1.1 GiB; `sliding_block_on_slab.toml` 3.9 ms both;
/// `block_stack.toml` 12.8 against 12.2 ms.
pub(super) fn zone_preference(kind: DelassusKind, zone_iterates: bool) -> ZoneStorage {
    match kind {
        DelassusKind::Flexibility => ZoneStorage::Flexibility,
        DelassusKind::Auto if zone_iterates => ZoneStorage::Flexibility,
        _ => ZoneStorage::Full,
    }
}

/// What [`Delassus::condense_zone`] keeps of a zone of `z` dofs: the `preferred` storage
/// if it fits the dense budget, else the other one if it does, else nothing.
pub(super) fn zone_storage(
    n: usize,
    z: usize,
    m: usize,
    per: usize,
    preferred: ZoneStorage,
) -> Option<ZoneStorage> {
    let fits = |s: ZoneStorage| match s {
        ZoneStorage::Full => zone_bytes(n, z, m, per) <= AUTO_DENSE_MAX_BYTES,
        ZoneStorage::Flexibility => flexibility_bytes(n, z, m, per) <= AUTO_DENSE_MAX_BYTES,
    };
    let other = match preferred {
        ZoneStorage::Full => ZoneStorage::Flexibility,
        ZoneStorage::Flexibility => ZoneStorage::Full,
    };
    [preferred, other].into_iter().find(|&s| fits(s))
}

/// The phrase of a path: the zone's dofs, dense, or the per-active-column pool.
pub(super) fn describe_path(
    zone: Option<(usize, ZoneStorage)>,
    dense: bool,
    n: usize,
    m: usize,
    cap: usize,
) -> String {
    if let Some((z, storage)) = zone {
        let (kept, corrections) = match storage {
            ZoneStorage::Full => (format!("Â⁻¹S {n}×{z}"), "(Â⁻¹S)(Bx)"),
            ZoneStorage::Flexibility => (
                format!("F = SᵀÂ⁻¹S {z}×{z} (Â⁻¹S {n}×{z} not kept)"),
                "by one sparse solve",
            ),
        };
        format!(
            "Delassus dense on the contact zone: {kept} condensed once ({z} zone \
             dofs), W = BᵀFB {m}×{m} re-formed per linearization without a solve \
             (constant blocks once), corrections {corrections}"
        )
    } else if dense {
        format!("Delassus dense: Â⁻¹G {n}×{m} and W {m}×{m} condensed per linearization")
    } else {
        format!(
            "Delassus per-active-column: W columns computed when a contact first \
             activates (pool of {cap} columns of {m}), corrections by one sparse solve"
        )
    }
}

impl Delassus {
    /// Where [`Delassus::new`], [`Delassus::limit_columns`] and
    /// [`Delassus::condense_zone`] put the Delassus data of `m` contact rows on `n` dofs,
    /// and its bytes: the same decisions, with nothing formed (`zone`: the contact zone's
    /// dofs when the set asks to be condensed, [`crate::contact::ContactSet::condensed`]).
    #[allow(clippy::too_many_arguments)]
    pub fn plan(
        n: usize,
        m: usize,
        (kind, pool): (DelassusKind, usize),
        with_d: bool,
        g_constant: bool,
        zone: Option<usize>,
        limit: usize,
        zone_iterates: bool,
    ) -> DelassusPlan {
        let per = if with_d { 2 } else { 1 };
        let dense = choose_dense(kind, n, m, per, g_constant);
        let mut cap = pool_cap(dense, pool, m, per);
        if !dense && pool == 0 && cap > limit.max(1) {
            cap = limit.max(1);
        }
        let z = zone
            .filter(|&z| {
                (dense || matches!(kind, DelassusKind::Auto | DelassusKind::Flexibility))
                    && !g_constant
                    && z > 0
            })
            .and_then(|z| {
                zone_storage(n, z, m, per, zone_preference(kind, zone_iterates)).map(|s| (z, s))
            });
        let (n8, m8) = (n as u64 * 8, m as u64 * 8);
        let per = per as u64;
        let setup_bytes = match z {
            Some((z, ZoneStorage::Flexibility)) => {
                flexibility_scratch_bytes(n, z, per as usize) as u64
            }
            _ => 0,
        };
        let bytes = match z {
            Some((z, ZoneStorage::Full)) => zone_bytes(n, z, m, per as usize) as u64,
            Some((z, ZoneStorage::Flexibility)) => {
                (flexibility_bytes(n, z, m, per as usize)
                    + flexibility_scratch_bytes(n, z, per as usize)) as u64
            }
            None if dense => n8 * m as u64 * per + m8 * m as u64 * (1 + 2 * u64::from(with_d)),
            None => m8 * cap as u64 * per + n8 * SOLVE_BLOCK.min(m).max(2) as u64 * per + 2 * n8,
        };
        DelassusPlan {
            zone_flexibilities: matches!(z, Some((_, ZoneStorage::Flexibility))),
            setup_bytes,
            dense: dense || z.is_some(),
            describe: describe_path(
                z,
                dense || z.is_some(),
                n,
                m,
                if z.is_some() { m } else { cap },
            ),
            bytes,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The zone storage decisions at the sizes the user guide quotes (docs/bodies.md): the two 8³ cubes keep
    /// `Y`, `E`; the two 20³ cubes (54 243 dofs, 2 646 zone dofs, 441 rows, with `W_D`)
    /// would need 2.3 GB of `n × z` blocks and keep the flexibilities (112 MB); the two
    /// 40³ cubes (408 483 dofs, 10 086 zone dofs, 1 681 rows) keep the flexibilities
    /// (1.9 GB, under the 2 GiB budget, plus 0.8 GB of set-up scratch in the plan); a
    /// face of 100 × 100 nodes on both sides (60 000 zone dofs: 58 GB) is not condensed.
    #[test]
    fn zone_storage_follows_the_budget() {
        assert_eq!(
            zone_storage(4_131, 486, 81, 2, ZoneStorage::Full),
            Some(ZoneStorage::Full)
        );
        assert_eq!(
            zone_storage(4_131, 486, 81, 2, ZoneStorage::Flexibility),
            Some(ZoneStorage::Flexibility)
        );
        assert!(zone_bytes(54_243, 2_646, 441, 2) > AUTO_DENSE_MAX_BYTES);
        assert_eq!(
            zone_storage(54_243, 2_646, 441, 2, ZoneStorage::Full),
            Some(ZoneStorage::Flexibility)
        );
        let b = flexibility_bytes(54_243, 2_646, 441, 2);
        assert!((110 << 20..130 << 20).contains(&b), "{b}");
        assert_eq!(
            zone_storage(408_483, 10_086, 1_681, 2, ZoneStorage::Full),
            Some(ZoneStorage::Flexibility)
        );
        for s in [ZoneStorage::Full, ZoneStorage::Flexibility] {
            assert_eq!(zone_storage(1_000_000, 60_000, 10_000, 2, s), None);
        }
        assert_eq!(
            zone_preference(DelassusKind::Auto, true),
            ZoneStorage::Flexibility
        );
        assert_eq!(
            zone_preference(DelassusKind::Auto, false),
            ZoneStorage::Full
        );
        assert_eq!(
            zone_preference(DelassusKind::Dense, true),
            ZoneStorage::Full
        );
        let plan = Delassus::plan(
            408_483,
            1_681,
            (DelassusKind::Auto, 0),
            true,
            false,
            Some(10_086),
            4096,
            true,
        );
        let expect = flexibility_bytes(408_483, 10_086, 1_681, 2)
            + flexibility_scratch_bytes(408_483, 10_086, 2);
        assert_eq!(plan.bytes, expect as u64);
        assert!(plan.describe.contains("not kept"), "{}", plan.describe);
    }
}
