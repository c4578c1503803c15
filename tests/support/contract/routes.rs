//! The routes an axum router serves, read from its source text.
//!
//! Reads every `.route("PATH", get(h).post(h2)...)` call and returns one
//! `(METHOD, PATH)` pair per method-router function (`get`, `post`, `put`, `patch`,
//! `delete`, `head`, `options`, `trace`) called at the top level of the second
//! argument. The route-role markers `reads(..)`, `writes(..)`, `admin(..)` and a method
//! router's `.merge(..)` are looked through. Anything it does not understand
//! (`.route_service`, `.nest`, a router's `.merge`, `any(..)`, a path that is not a
//! string literal) is an error rather than a route silently missed.

const METHODS: &[&str] = &[
    "get", "post", "put", "patch", "delete", "head", "options", "trace",
];

/// `(METHOD, PATH)` for every route in `source`, in order of appearance.
pub fn routes(source: &str) -> Result<Vec<(String, String)>, String> {
    let code = strip_comments(source);
    for unsupported in [".route_service(", ".nest(", ".nest_service("] {
        if code.contains(unsupported) {
            return Err(format!(
                "the router uses {unsupported}..); teach tests/support/contract/routes.rs \
                 to read it"
            ));
        }
    }
    let mut out = Vec::new();
    let mut merges = 0;
    let mut rest = code.as_str();
    while let Some(i) = rest.find(".route(") {
        rest = &rest[i + ".route(".len()..];
        let (path, after) = string_literal(rest)?;
        let after = after.trim_start();
        let after = after
            .strip_prefix(',')
            .ok_or_else(|| format!("expected ',' after the path {path:?}"))?;
        let (calls, tail) = top_level_calls(after)?;
        let methods = method_names(calls, &mut merges)?;
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
    if code.matches(".merge(").count() != merges {
        return Err(
            "the router merges routers (.merge outside a .route call); teach \
                    tests/support/contract/routes.rs to read it"
                .into(),
        );
    }
    Ok(out)
}

/// The method-router functions among `calls`, looking through role markers and
/// `.merge(..)` (counted in `merges`).
fn method_names(calls: Vec<Call>, merges: &mut usize) -> Result<Vec<String>, String> {
    let mut out = Vec::new();
    for (name, arg) in calls {
        match name.as_str() {
            "layer" | "route_layer" | "with_state" => {}
            "reads" | "writes" | "admin" | "merge" => {
                if name == "merge" {
                    *merges += 1;
                }
                let (inner, _) = top_level_calls(&format!("{arg})"))?;
                out.extend(method_names(inner, merges)?);
            }
            _ => out.push(name),
        }
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

/// A function or method called, and its argument text.
type Call = (String, String);

/// The functions and methods called at depth 0 of `s`, each with its argument text, up
/// to the `)` that closes the enclosing call; and the text after that `)`.
fn top_level_calls(s: &str) -> Result<(Vec<Call>, &str), String> {
    let mut depth = 0usize;
    let mut calls: Vec<Call> = Vec::new();
    let mut open_at = 0usize;
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
                    calls.push((last_ident.clone(), String::new()));
                    open_at = i + 1;
                }
                depth += 1;
            }
            ')' | ']' | '}' => {
                if depth == 0 {
                    return Ok((calls, &s[i + 1..]));
                }
                depth -= 1;
                if depth == 0
                    && c == ')'
                    && let Some(last) = calls.last_mut()
                {
                    last.1 = s[open_at..i].to_string();
                }
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
                .route("/e", reads(get(e)).merge(writes(put(e2).delete(e3))))
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
            ("GET", "/e"),
            ("PUT", "/e"),
            ("DELETE", "/e"),
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
        assert!(routes(r#".route("/a", get(h)).merge(other)"#).is_err());
    }
}
