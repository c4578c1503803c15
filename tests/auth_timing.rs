//! The time `Tokens::role_of` takes must not depend on how much of a real token a guess
//! shares.
//!
//! Why this would fail for an early-exit comparison: with 4 KiB tokens, comparing a guess
//! byte by byte against the raw token (`==` on strings, `memcmp`) stops at the first
//! differing byte. A guess that differs in its first byte is rejected after one byte; a guess
//! that shares the first 4095 bytes is rejected only after reading all of them, thousands of
//! times more work, and far slower even with vectorised comparison. The ratio of the two
//! median times would then lie far outside the band asserted here. `role_of` instead hashes
//! every guess in full (same length, same work) and compares fixed-size digests in constant
//! time, so both kinds of guess cost the same.
//!
//! Only a ratio measured within one run is asserted, from interleaved rounds (so drift in
//! machine load affects both kinds alike), with a generous band: no absolute times.

use std::hint::black_box;
use std::time::{Duration, Instant};

use winged::server::auth::{Role, Tokens};

const TOKEN_LEN: usize = 4096;
const ROUNDS: usize = 301;
const CALLS_PER_BATCH: usize = 16;

fn median(mut v: Vec<Duration>) -> Duration {
    v.sort();
    v[v.len() / 2]
}

/// The time of `CALLS_PER_BATCH` lookups of `guess`.
fn batch(tokens: &Tokens, guess: &str) -> Duration {
    let start = Instant::now();
    for _ in 0..CALLS_PER_BATCH {
        assert_eq!(black_box(tokens.role_of(black_box(guess))), None);
    }
    start.elapsed()
}

#[test]
fn role_of_timing_does_not_depend_on_the_prefix_of_a_guess() {
    // A printable 4 KiB secret, and a few other tokens so that every entry is visited.
    let secret: String = (0..TOKEN_LEN)
        .map(|i| char::from(b'A' + (i * 7 % 26) as u8))
        .collect();
    let flags = vec![
        format!("admin:{secret}"),
        format!("read:{}", "r".repeat(TOKEN_LEN)),
        format!("write:{}", "w".repeat(TOKEN_LEN)),
    ];
    let tokens = Tokens::from_sources(&flags, None, None).expect("valid tokens");
    assert_eq!(tokens.role_of(&secret), Some(Role::Admin));

    // Same length as the secret: one shares all but the last byte, one differs at once.
    let mut near = secret.clone();
    near.pop();
    near.push('#');
    let far = format!("#{}", &secret[1..]);
    assert_eq!((near.len(), far.len()), (TOKEN_LEN, TOKEN_LEN));

    // Warm up caches and frequency scaling before measuring.
    for _ in 0..20 {
        batch(&tokens, &near);
        batch(&tokens, &far);
    }

    let mut near_times = Vec::with_capacity(ROUNDS);
    let mut far_times = Vec::with_capacity(ROUNDS);
    for round in 0..ROUNDS {
        // Alternate which kind goes first, so neither always follows the other.
        if round % 2 == 0 {
            near_times.push(batch(&tokens, &near));
            far_times.push(batch(&tokens, &far));
        } else {
            far_times.push(batch(&tokens, &far));
            near_times.push(batch(&tokens, &near));
        }
    }
    let (near_median, far_median) = (median(near_times), median(far_times));
    let ratio = near_median.as_secs_f64() / far_median.as_secs_f64().max(1e-12);
    eprintln!("near/far median ratio {ratio:.3}");
    assert!(
        (0.5..2.0).contains(&ratio),
        "a guess sharing a {}-byte prefix took {near_median:?} per batch, one differing at \
         the first byte {far_median:?}: ratio {ratio:.3}",
        TOKEN_LEN - 1
    );
}
