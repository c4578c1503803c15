//! Whole numbers written with a fraction of zeros (`2.0`) read as the integers they
//! spell, as JSON Schema reads them: `{"face": 12.0}` names face 12.
//!
//! The request types take ids, counts and sizes in pixels as integers, and serde refuses
//! a JSON number with a fraction part for them. [`whole_numbers`] rewrites, in the request
//! text and before it is parsed, every number token of the form `-?DIGITS.ZEROS` (no
//! exponent) to `-?DIGITS`. The rewrite changes no value a floating-point field reads: an
//! integer token and the same digits followed by `.0` parse to the same `f64` (both round
//! the same exact value to nearest). `-0.0` is left as it is, so that its sign survives.

use std::borrow::Cow;

/// `json` with every number token `-?DIGITS.ZEROS` written `-?DIGITS` (except `-0.0…`).
///
/// Precondition: none; text that is not JSON is passed through with the same rewrite of
/// anything outside double-quoted strings, and the parser refuses it afterwards.
/// Postcondition: string contents are untouched; the answer borrows `json` when nothing
/// needed rewriting. Linear in the length, one allocation at most.
pub fn whole_numbers(json: &[u8]) -> Cow<'_, [u8]> {
    let mut out: Option<Vec<u8>> = None;
    // Bytes of `json` before `copied` are already in `out`.
    let mut copied = 0;
    let mut i = 0;
    while i < json.len() {
        match json[i] {
            b'"' => i = string_end(json, i),
            b'-' | b'0'..=b'9' => {
                let end = token_end(json, i);
                if let Some(dot) = zero_fraction(&json[i..end]) {
                    let out = out.get_or_insert_with(|| Vec::with_capacity(json.len()));
                    out.extend_from_slice(&json[copied..i + dot]);
                    copied = end;
                }
                i = end;
            }
            _ => i += 1,
        }
    }
    match out {
        None => Cow::Borrowed(json),
        Some(mut out) => {
            out.extend_from_slice(&json[copied..]);
            Cow::Owned(out)
        }
    }
}

/// The index just past the string that starts with the quote at `start`.
fn string_end(json: &[u8], start: usize) -> usize {
    let mut i = start + 1;
    while i < json.len() {
        match json[i] {
            b'\\' => i += 2,
            b'"' => return i + 1,
            _ => i += 1,
        }
    }
    json.len()
}

/// The index just past the number token that starts at `start`.
fn token_end(json: &[u8], start: usize) -> usize {
    let mut i = start + 1;
    while i < json.len() && matches!(json[i], b'0'..=b'9' | b'.' | b'e' | b'E' | b'+' | b'-') {
        i += 1;
    }
    i
}

/// Where the `.` is, when `token` is `-?DIGITS.ZEROS` and not a negative zero.
fn zero_fraction(token: &[u8]) -> Option<usize> {
    let dot = token.iter().position(|&b| b == b'.')?;
    let (whole, fraction) = (&token[..dot], &token[dot + 1..]);
    let digits = whole.strip_prefix(b"-").unwrap_or(whole);
    let all = |s: &[u8], f: fn(&u8) -> bool| !s.is_empty() && s.iter().all(f);
    let negative_zero = whole.first() == Some(&b'-') && digits.iter().all(|&b| b == b'0');
    (all(digits, u8::is_ascii_digit) && all(fraction, |&b| b == b'0') && !negative_zero)
        .then_some(dot)
}

#[cfg(test)]
mod tests {
    use super::whole_numbers;

    fn rewrite(s: &str) -> String {
        String::from_utf8(whole_numbers(s.as_bytes()).into_owned()).unwrap()
    }

    #[test]
    fn whole_numbers_lose_their_zero_fraction() {
        assert_eq!(
            rewrite(r#"{"face":12.0,"v":[1.00,-3.0]}"#),
            r#"{"face":12,"v":[1,-3]}"#
        );
        assert_eq!(rewrite("0.0"), "0");
        assert_eq!(rewrite("[1.0, 2.0]"), "[1, 2]");
    }

    #[test]
    fn other_numbers_strings_and_negative_zero_are_kept() {
        for s in [
            r#"{"x":1.5,"y":1e3,"z":2.0e1,"w":-0.0,"n":"12.0","e":"a\"1.0"}"#,
            "[1.01, 10, -0.00, 1.]",
        ] {
            assert!(matches!(
                whole_numbers(s.as_bytes()),
                std::borrow::Cow::Borrowed(_)
            ));
        }
    }

    #[test]
    fn the_rewrite_changes_no_floating_point_value() {
        for s in [
            "9007199254740993.0",
            "18446744073709551617.0",
            "12345678901234567890123.0",
        ] {
            let before: f64 = serde_json::from_str(s).unwrap();
            let after: f64 = serde_json::from_str(&rewrite(s)).unwrap();
            assert_eq!(before.to_bits(), after.to_bits(), "{s}");
        }
        let id: u64 = serde_json::from_str(&rewrite("42.000")).unwrap();
        assert_eq!(id, 42);
    }
}
