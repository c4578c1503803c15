//! The routes an axum router serves, read from its source text.
//!
//! Reads every `.route("PATH", get(h).post(h2)...)` call and returns one
//! `(METHOD, PATH)` pair per method-router function (`get`, `post`, `put`, `patch`,
//! `delete`, `head`, `options`, `trace`) called at the top level of the second
//! argument. Anything it does not understand (`.route_service`, `.nest`, `.merge`,
//! `any(..)`, a path that is not a string literal) is an error rather than a route
//! silently missed.

const METHODS: &[&str] = &[
    "get", "post", "put", "patch", "delete", "head", "options", "trace",
];

/// `(METHOD, PATH)` for every route in `source`, in order of appearance.
pub fn routes(source: &str) -> Result<Vec<(String, String)>, String> {
    let code = strip_comments(source);
    for unsupported in [".route_service(", ".nest(", ".nest_service(", ".merge("] {
        if code.contains(unsupported) {
            return Err(format!(
                "the router uses {unsupported}..); teach tests/contract_support/routes.rs \
                 to read it"
            ));
        }
    }
    let mut out = Vec::new();
    let mut rest = code.as_str();
    while let Some(i) = rest.find(".route(") {
        rest = &rest[i + ".route(".len()..];
        let (path, after) = string_literal(rest)?;
        let after = after.trim_start();
        let after = after
            .strip_prefix(',')
            .ok_or_else(|| format!("expected ',' after the path {path:?}"))?;
        let (methods, tail) = top_level_calls(after)?;
        let methods: Vec<String> = methods
            .into_iter()
            .filter(|m| m != "layer" && m != "with_state")
            .collect();
        if methods.is_empty() {
            return Err(format!("no method router found for {path:?}"));
        }
        for m in methods {
            if !METHODS.contains(&m.as_str()) {
                return Err(format!(
                    "route {path:?} uses {m}(..), which is not a method router this \
                     parser knows"
                ));
            }
            out.push((m.to_uppercase(), path.clone()));
        }
        rest = tail;
    }
    Ok(out)
}

/// Removes `//` and `/* */` comments outside string literals.
fn strip_comments(src: &str) -> String {
    let mut out = String::with_capacity(src.len());
    let b = src.as_bytes();
    let mut i = 0;
    let mut in_str = false;
    while i < b.len() {
        let c = b[i];
        if in_str {
            out.push(c as char);
            if c == b'\\' && i + 1 < b.len() {
                out.push(b[i + 1] as char);
                i += 2;
                continue;
            }
            if c == b'"' {
                in_str = false;
            }
            i += 1;
        } else if c == b'"' {
            in_str = true;
            out.push('"');
            i += 1;
        } else if src[i..].starts_with("//") {
            while i < b.len() && b[i] != b'\n' {
                i += 1;
            }
        } else if src[i..].starts_with("/*") {
            i = src[i + 2..].find("*/").map_or(b.len(), |j| i + 2 + j + 2);
        } else {
            // Keep multi-byte characters whole.
            let ch = src[i..].chars().next().unwrap_or(' ');
            out.push(ch);
            i += ch.len_utf8();
        }
    }
    out
}

/// A `"..."` literal at the start of `s` (after white space), and what follows it.
fn string_literal(s: &str) -> Result<(String, &str), String> {
    let s = s.trim_start();
    let body = s
        .strip_prefix('"')
        .ok_or_else(|| format!("expected a string literal path at {:?}", head(s)))?;
    let end = body
        .find('"')
        .ok_or_else(|| "unterminated string literal".to_string())?;
    let lit = &body[..end];
    if lit.contains('\\') {
        return Err(format!("escapes in route paths are not supported: {lit:?}"));
    }
    Ok((lit.to_string(), &body[end + 1..]))
}

/// The names of functions and methods called at depth 0 of `s`, up to the `)` that
/// closes the enclosing call; and the text after that `)`.
fn top_level_calls(s: &str) -> Result<(Vec<String>, &str), String> {
    let mut depth = 0usize;
    let mut calls = Vec::new();
    let mut ident = String::new();
    let mut last_ident = String::new();
    let mut in_str = false;
    let mut chars = s.char_indices().peekable();
    while let Some((i, c)) = chars.next() {
        if in_str {
            if c == '\\' {
                chars.next();
            } else if c == '"' {
                in_str = false;
            }
            continue;
        }
        if c.is_alphanumeric() || c == '_' {
            ident.push(c);
            continue;
        }
        if !ident.is_empty() {
            last_ident = std::mem::take(&mut ident);
        }
        match c {
            '"' => in_str = true,
            '(' | '[' | '{' => {
                if c == '(' && depth == 0 && !last_ident.is_empty() {
                    calls.push(last_ident.clone());
                }
                depth += 1;
            }
            ')' | ']' | '}' => {
                if depth == 0 {
                    return Ok((calls, &s[i + 1..]));
                }
                depth -= 1;
            }
            c if c.is_whitespace() => continue,
            _ => {}
        }
        last_ident.clear();
    }
    Err("unbalanced parentheses in a .route(..) call".into())
}

fn head(s: &str) -> &str {
    &s[..s.len().min(40)]
}

#[cfg(test)]
mod tests {
    use super::routes;

    #[test]
    fn reads_methods_chained_and_nested() {
        let src = r#"
            Router::new()
                .route("/a", get(a)) // .route("/commented", get(x))
                .route(
                    "/b/{id}",
                    get(b).patch(h::patch_b).delete(del),
                )
                .route("/c", axum::routing::post(c).layer(DefaultBodyLimit::max(f(1))))
                /* .route("/d", put(d)) */
                .fallback(nf)
        "#;
        let r = routes(src).unwrap();
        let want = [
            ("GET", "/a"),
            ("GET", "/b/{id}"),
            ("PATCH", "/b/{id}"),
            ("DELETE", "/b/{id}"),
            ("POST", "/c"),
        ];
        assert_eq!(
            r,
            want.map(|(m, p)| (m.to_string(), p.to_string())).to_vec()
        );
    }

    #[test]
    fn refuses_what_it_cannot_read() {
        assert!(routes(r#".route("/a", any(h))"#).is_err());
        assert!(routes(r#".route(PATH, get(h))"#).is_err());
        assert!(routes(r#".nest("/v2", other())"#).is_err());
        assert!(routes(r#".route("/a", get(h)"#).is_err());
    }
}
