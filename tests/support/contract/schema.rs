//! A validator for the subset of JSON Schema 2020-12 that `proto/openapi.yaml` uses.
//!
//! Implemented: `$ref` (local `#/...` pointers), `type` (one or several), `enum`,
//! `const`, `properties`, `required`, `additionalProperties`, `items`, `minItems`,
//! `maxItems`, `minimum`, `maximum`, `exclusiveMinimum`, `exclusiveMaximum`,
//! `minLength`, `maxLength`, `pattern`, `allOf`, `anyOf`, `oneOf`, `not`, and OpenAPI's
//! `discriminator` (used to pick the branch whose errors are reported, and checked for
//! consistency with its `oneOf`). Annotations (`description`, `default`, ...) are
//! ignored. Any other keyword is an error, so that the contract cannot quietly use a
//! keyword this validator would skip.
//!
//! One deliberate difference from the standard: `integer` means a JSON number written
//! without a fraction or exponent (`3`, not `3.0`), because ids must be JSON integers.

use serde_json::{Map, Value};

/// Keywords that constrain instances and are implemented here.
const ASSERTIONS: &[&str] = &[
    "$ref",
    "type",
    "enum",
    "const",
    "properties",
    "required",
    "additionalProperties",
    "items",
    "minItems",
    "maxItems",
    "minimum",
    "maximum",
    "exclusiveMinimum",
    "exclusiveMaximum",
    "minLength",
    "maxLength",
    "pattern",
    "allOf",
    "anyOf",
    "oneOf",
    "not",
    "discriminator",
];

/// Keywords that only annotate.
const ANNOTATIONS: &[&str] = &[
    "description",
    "title",
    "default",
    "examples",
    "example",
    "format",
    "deprecated",
    "readOnly",
    "writeOnly",
    "$comment",
    "externalDocs",
];

const TYPES: &[&str] = &[
    "null", "boolean", "object", "array", "number", "integer", "string",
];

/// Validates instances against schemas of one document (whose `$ref`s it resolves).
pub struct Validator<'a> {
    doc: &'a Value,
}

impl<'a> Validator<'a> {
    /// A validator resolving `$ref`s in `doc`.
    pub fn new(doc: &'a Value) -> Self {
        Validator { doc }
    }

    /// The value a local reference `#/a/b` points at.
    pub fn resolve(&self, reference: &str) -> Result<&'a Value, String> {
        let pointer = reference
            .strip_prefix('#')
            .ok_or_else(|| format!("only local references are supported: {reference}"))?;
        self.doc
            .pointer(pointer)
            .ok_or_else(|| format!("unresolved reference {reference}"))
    }

    /// Follows `$ref` chains (an object that is only a reference plus annotations).
    pub fn deref(&self, mut v: &'a Value) -> Result<&'a Value, String> {
        for _ in 0..32 {
            match v.get("$ref").and_then(Value::as_str) {
                Some(r) => v = self.resolve(r)?,
                None => return Ok(v),
            }
        }
        Err("reference chain too long".into())
    }

    /// Every way `instance` fails `schema`; empty if it conforms.
    pub fn errors(&self, schema: &Value, instance: &Value) -> Vec<String> {
        let mut errs = Vec::new();
        self.check(schema, instance, "", &mut errs, 0);
        errs
    }

    /// `Ok` if `instance` conforms to `schema`, else the errors joined.
    pub fn validate(&self, schema: &Value, instance: &Value) -> Result<(), String> {
        let errs = self.errors(schema, instance);
        if errs.is_empty() {
            Ok(())
        } else {
            Err(errs.join("\n"))
        }
    }

    fn check(&self, schema: &Value, v: &Value, at: &str, errs: &mut Vec<String>, depth: usize) {
        if depth > 64 {
            errs.push(format!("{at}: schema nesting too deep (a $ref cycle?)"));
            return;
        }
        let s = match schema {
            Value::Bool(true) => return,
            Value::Bool(false) => {
                errs.push(format!("{at}: no value is allowed here"));
                return;
            }
            Value::Object(s) => s,
            other => {
                errs.push(format!("{at}: a schema must be an object, not {other}"));
                return;
            }
        };
        for key in s.keys() {
            if !ASSERTIONS.contains(&key.as_str()) && !ANNOTATIONS.contains(&key.as_str()) {
                errs.push(format!("{at}: schema keyword {key:?} is not supported"));
            }
        }
        let at_or_root = if at.is_empty() { "/" } else { at };
        if let Some(r) = s.get("$ref") {
            match r.as_str().map(|r| self.resolve(r)) {
                Some(Ok(target)) => self.check(target, v, at, errs, depth + 1),
                Some(Err(e)) => errs.push(format!("{at_or_root}: {e}")),
                None => errs.push(format!("{at_or_root}: $ref must be a string")),
            }
        }
        if let Some(t) = s.get("type") {
            let names: Vec<&str> = match t {
                Value::String(n) => vec![n.as_str()],
                Value::Array(a) => a.iter().filter_map(Value::as_str).collect(),
                _ => vec![],
            };
            if !names.iter().any(|n| is_type(v, n)) {
                errs.push(format!(
                    "{at_or_root}: expected {}, found {}",
                    names.join(" or "),
                    kind(v)
                ));
                // Further checks would only repeat the type error.
                return;
            }
        }
        if let Some(c) = s.get("const")
            && !json_eq(c, v)
        {
            errs.push(format!("{at_or_root}: expected {c}, found {v}"));
        }
        if let Some(Value::Array(options)) = s.get("enum")
            && !options.iter().any(|o| json_eq(o, v))
        {
            errs.push(format!(
                "{at_or_root}: {v} is not one of {}",
                Value::Array(options.clone())
            ));
        }
        if let Some(n) = v.as_f64() {
            let bound = |k: &str| s.get(k).and_then(Value::as_f64);
            if let Some(m) = bound("minimum")
                && n < m
            {
                errs.push(format!("{at_or_root}: {v} is below the minimum {m}"));
            }
            if let Some(m) = bound("maximum")
                && n > m
            {
                errs.push(format!("{at_or_root}: {v} is above the maximum {m}"));
            }
            if let Some(m) = bound("exclusiveMinimum")
                && n <= m
            {
                errs.push(format!("{at_or_root}: {v} is not above {m}"));
            }
            if let Some(m) = bound("exclusiveMaximum")
                && n >= m
            {
                errs.push(format!("{at_or_root}: {v} is not below {m}"));
            }
        }
        if let Value::String(text) = v {
            let len = text.chars().count() as u64;
            if let Some(m) = s.get("minLength").and_then(Value::as_u64)
                && len < m
            {
                errs.push(format!("{at_or_root}: {v} is shorter than {m} characters"));
            }
            if let Some(m) = s.get("maxLength").and_then(Value::as_u64)
                && len > m
            {
                errs.push(format!("{at_or_root}: {v} is longer than {m} characters"));
            }
            if let Some(p) = s.get("pattern").and_then(Value::as_str) {
                match regex::Regex::new(p) {
                    Ok(re) if re.is_match(text) => {}
                    Ok(_) => errs.push(format!("{at_or_root}: {v} does not match {p:?}")),
                    Err(e) => errs.push(format!("{at_or_root}: pattern {p:?}: {e}")),
                }
            }
        }
        if let Value::Array(items) = v {
            let n = items.len() as u64;
            if let Some(m) = s.get("minItems").and_then(Value::as_u64)
                && n < m
            {
                errs.push(format!("{at_or_root}: {n} items, fewer than {m}"));
            }
            if let Some(m) = s.get("maxItems").and_then(Value::as_u64)
                && n > m
            {
                errs.push(format!("{at_or_root}: {n} items, more than {m}"));
            }
            if let Some(item) = s.get("items") {
                for (i, x) in items.iter().enumerate() {
                    self.check(item, x, &format!("{at}/{i}"), errs, depth + 1);
                }
            }
        }
        if let Value::Object(obj) = v {
            self.check_object(s, obj, at, errs, depth);
        }
        if let Some(Value::Array(all)) = s.get("allOf") {
            for sub in all {
                self.check(sub, v, at, errs, depth + 1);
            }
        }
        if let Some(Value::Array(any)) = s.get("anyOf")
            && !any
                .iter()
                .any(|sub| self.errors_at(sub, v, at, depth).is_empty())
        {
            errs.push(format!("{at_or_root}: matches none of anyOf"));
        }
        if let Some(Value::Array(one)) = s.get("oneOf") {
            self.check_one_of(s, one, v, at, errs, depth);
        }
        if let Some(not) = s.get("not")
            && self.errors_at(not, v, at, depth).is_empty()
        {
            errs.push(format!("{at_or_root}: matches a schema it must not match"));
        }
    }

    fn errors_at(&self, schema: &Value, v: &Value, at: &str, depth: usize) -> Vec<String> {
        let mut errs = Vec::new();
        self.check(schema, v, at, &mut errs, depth + 1);
        errs
    }

    fn check_object(
        &self,
        s: &Map<String, Value>,
        obj: &Map<String, Value>,
        at: &str,
        errs: &mut Vec<String>,
        depth: usize,
    ) {
        let at_or_root = if at.is_empty() { "/" } else { at };
        if let Some(Value::Array(required)) = s.get("required") {
            for r in required.iter().filter_map(Value::as_str) {
                if !obj.contains_key(r) {
                    errs.push(format!("{at_or_root}: missing required property {r:?}"));
                }
            }
        }
        let props = s.get("properties").and_then(Value::as_object);
        for (k, x) in obj {
            let here = format!("{at}/{}", k.replace('~', "~0").replace('/', "~1"));
            match props.and_then(|p| p.get(k)) {
                Some(sub) => self.check(sub, x, &here, errs, depth + 1),
                None => match s.get("additionalProperties") {
                    Some(Value::Bool(false)) => {
                        errs.push(format!("{at_or_root}: property {k:?} is not allowed"));
                    }
                    Some(sub @ Value::Object(_)) => self.check(sub, x, &here, errs, depth + 1),
                    _ => {}
                },
            }
        }
    }

    fn check_one_of(
        &self,
        s: &Map<String, Value>,
        one: &[Value],
        v: &Value,
        at: &str,
        errs: &mut Vec<String>,
        depth: usize,
    ) {
        let at_or_root = if at.is_empty() { "/" } else { at };
        let results: Vec<Vec<String>> = one
            .iter()
            .map(|sub| self.errors_at(sub, v, at, depth))
            .collect();
        let passing = results.iter().filter(|e| e.is_empty()).count();
        if passing == 1 {
            return;
        }
        if passing > 1 {
            errs.push(format!(
                "{at_or_root}: matches {passing} branches of oneOf, not exactly one"
            ));
            return;
        }
        // No branch matches: report the branch the discriminator names, if any, so that
        // the message says what is wrong with it rather than with every branch.
        if let Some(d) = s.get("discriminator") {
            let prop = d.get("propertyName").and_then(Value::as_str).unwrap_or("");
            match v.get(prop).and_then(Value::as_str) {
                None => errs.push(format!(
                    "{at_or_root}: missing discriminator property {prop:?}"
                )),
                Some(tag) => {
                    let target = d
                        .get("mapping")
                        .and_then(|m| m.get(tag))
                        .and_then(Value::as_str);
                    match target.and_then(|t| one.iter().position(|b| ref_of(b) == Some(t))) {
                        Some(i) => errs.extend(results[i].iter().cloned()),
                        None => errs.push(format!(
                            "{at_or_root}: {prop} {tag:?} is none of the mapped variants"
                        )),
                    }
                }
            }
            return;
        }
        errs.push(format!("{at_or_root}: matches no branch of oneOf"));
        for (i, e) in results.iter().enumerate() {
            for line in e {
                errs.push(format!("  (oneOf branch {i}) {line}"));
            }
        }
    }

    /// Problems with a schema itself: unsupported keywords, unresolved references,
    /// malformed keyword values, and discriminators inconsistent with their `oneOf`.
    pub fn schema_problems(&self, schema: &Value, at: &str) -> Vec<String> {
        let mut out = Vec::new();
        self.lint(schema, at, &mut out, 0);
        out
    }

    fn lint(&self, schema: &Value, at: &str, out: &mut Vec<String>, depth: usize) {
        if depth > 64 {
            return;
        }
        let s = match schema {
            Value::Bool(_) => return,
            Value::Object(s) => s,
            _ => {
                out.push(format!("{at}: a schema must be an object or a boolean"));
                return;
            }
        };
        for (key, val) in s {
            let here = format!("{at}/{key}");
            match key.as_str() {
                "$ref" => match val.as_str() {
                    Some(r) => {
                        if let Err(e) = self.resolve(r) {
                            out.push(format!("{here}: {e}"));
                        }
                    }
                    None => out.push(format!("{here}: must be a string")),
                },
                "type" => {
                    let ok = match val {
                        Value::String(t) => TYPES.contains(&t.as_str()),
                        Value::Array(a) => a
                            .iter()
                            .all(|t| t.as_str().is_some_and(|t| TYPES.contains(&t))),
                        _ => false,
                    };
                    if !ok {
                        out.push(format!("{here}: unknown type {val}"));
                    }
                }
                "properties" => match val.as_object() {
                    Some(p) => {
                        for (name, sub) in p {
                            self.lint(sub, &format!("{here}/{name}"), out, depth + 1);
                        }
                    }
                    None => out.push(format!("{here}: must be an object")),
                },
                "required" => {
                    let props = s.get("properties").and_then(Value::as_object);
                    match val.as_array() {
                        Some(r) => {
                            for name in r {
                                match name.as_str() {
                                    Some(n) if props.is_some_and(|p| !p.contains_key(n)) => out
                                        .push(format!("{here}: {n:?} is required but not defined")),
                                    Some(_) => {}
                                    None => out.push(format!("{here}: names must be strings")),
                                }
                            }
                        }
                        None => out.push(format!("{here}: must be an array")),
                    }
                }
                "additionalProperties" | "items" | "not" => {
                    self.lint(val, &here, out, depth + 1);
                }
                "allOf" | "anyOf" | "oneOf" => match val.as_array() {
                    Some(a) if !a.is_empty() => {
                        for (i, sub) in a.iter().enumerate() {
                            self.lint(sub, &format!("{here}/{i}"), out, depth + 1);
                        }
                    }
                    _ => out.push(format!("{here}: must be a non-empty array")),
                },
                "enum" => {
                    if val.as_array().is_none_or(|a| a.is_empty()) {
                        out.push(format!("{here}: must be a non-empty array"));
                    }
                }
                "minItems" | "maxItems" | "minLength" | "maxLength" => {
                    if !val.is_u64() {
                        out.push(format!("{here}: must be a non-negative integer"));
                    }
                }
                "minimum" | "maximum" | "exclusiveMinimum" | "exclusiveMaximum" => {
                    if !val.is_number() {
                        out.push(format!("{here}: must be a number"));
                    }
                }
                "discriminator" => self.lint_discriminator(s, val, &here, out),
                "pattern" => match val.as_str().map(regex::Regex::new) {
                    Some(Ok(_)) => {}
                    Some(Err(e)) => out.push(format!("{here}: {e}")),
                    None => out.push(format!("{here}: must be a string")),
                },
                "const" => {}
                k if ANNOTATIONS.contains(&k) => {}
                k => out.push(format!("{here}: schema keyword {k:?} is not supported")),
            }
        }
    }

    /// A discriminator must sit beside a `oneOf` of references; its mapping must name
    /// exactly those references; each mapped schema must require the property and fix
    /// it to the mapping's key with `const`.
    fn lint_discriminator(
        &self,
        s: &Map<String, Value>,
        d: &Value,
        at: &str,
        out: &mut Vec<String>,
    ) {
        let Some(prop) = d.get("propertyName").and_then(Value::as_str) else {
            out.push(format!("{at}: propertyName is missing"));
            return;
        };
        let Some(one) = s.get("oneOf").and_then(Value::as_array) else {
            out.push(format!("{at}: a discriminator needs a oneOf beside it"));
            return;
        };
        let Some(mapping) = d.get("mapping").and_then(Value::as_object) else {
            out.push(format!("{at}: mapping is missing"));
            return;
        };
        let refs: Vec<&str> = one.iter().filter_map(ref_of).collect();
        if refs.len() != one.len() {
            out.push(format!("{at}: every oneOf branch must be a $ref"));
        }
        for r in &refs {
            if !mapping.values().any(|t| t.as_str() == Some(r)) {
                out.push(format!("{at}: oneOf branch {r} has no mapping"));
            }
        }
        for (tag, target) in mapping {
            let Some(t) = target.as_str() else {
                out.push(format!("{at}/mapping/{tag}: must be a string"));
                continue;
            };
            if !refs.contains(&t) {
                out.push(format!("{at}/mapping/{tag}: {t} is not a oneOf branch"));
            }
            let Ok(variant) = self.resolve(t) else {
                out.push(format!("{at}/mapping/{tag}: unresolved {t}"));
                continue;
            };
            let fixed = variant
                .pointer(&format!("/properties/{prop}/const"))
                .and_then(Value::as_str);
            if fixed != Some(tag.as_str()) {
                out.push(format!(
                    "{at}/mapping/{tag}: {t} must fix {prop:?} with const {tag:?}"
                ));
            }
            let required = variant
                .get("required")
                .and_then(Value::as_array)
                .is_some_and(|r| r.iter().any(|x| x.as_str() == Some(prop)));
            if !required {
                out.push(format!("{at}/mapping/{tag}: {t} must require {prop:?}"));
            }
        }
    }
}

fn ref_of(v: &Value) -> Option<&str> {
    v.get("$ref").and_then(Value::as_str)
}

fn is_type(v: &Value, name: &str) -> bool {
    match name {
        "null" => v.is_null(),
        "boolean" => v.is_boolean(),
        "object" => v.is_object(),
        "array" => v.is_array(),
        "number" => v.is_number(),
        "integer" => v.is_i64() || v.is_u64(),
        "string" => v.is_string(),
        _ => false,
    }
}

fn kind(v: &Value) -> String {
    match v {
        Value::Null => "null".into(),
        Value::Bool(_) => "a boolean".into(),
        Value::Number(n) if n.is_f64() => format!("the number {n}"),
        Value::Number(n) => format!("the integer {n}"),
        Value::String(s) => format!("the string {s:?}"),
        Value::Array(_) => "an array".into(),
        Value::Object(_) => "an object".into(),
    }
}

/// JSON equality with numbers compared by value (`1` equals `1.0`).
fn json_eq(a: &Value, b: &Value) -> bool {
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => match (x.as_i64(), y.as_i64()) {
            (Some(x), Some(y)) => x == y,
            _ => match (x.as_u64(), y.as_u64()) {
                (Some(x), Some(y)) => x == y,
                _ => x.as_f64() == y.as_f64(),
            },
        },
        (Value::Array(x), Value::Array(y)) => {
            x.len() == y.len() && x.iter().zip(y).all(|(p, q)| json_eq(p, q))
        }
        (Value::Object(x), Value::Object(y)) => {
            x.len() == y.len()
                && x.iter()
                    .all(|(k, p)| y.get(k).is_some_and(|q| json_eq(p, q)))
        }
        _ => a == b,
    }
}

#[cfg(test)]
mod tests {
    use serde_json::json;

    use super::Validator;

    fn doc() -> serde_json::Value {
        json!({
            "components": {"schemas": {
                "Id": {"type": "integer", "minimum": 1},
                "Vec3": {"type": "array", "items": {"type": "number"},
                         "minItems": 3, "maxItems": 3},
                "Box": {"type": "object", "required": ["type", "size"],
                        "additionalProperties": false,
                        "properties": {"type": {"const": "box"},
                                       "size": {"$ref": "#/components/schemas/Vec3"}}},
                "Ball": {"type": "object", "required": ["type", "radius"],
                         "additionalProperties": false,
                         "properties": {"type": {"const": "ball"},
                                        "radius": {"type": "number", "exclusiveMinimum": 0}}},
                "Shape": {"oneOf": [{"$ref": "#/components/schemas/Box"},
                                    {"$ref": "#/components/schemas/Ball"}],
                          "discriminator": {"propertyName": "type", "mapping": {
                              "box": "#/components/schemas/Box",
                              "ball": "#/components/schemas/Ball"}}},
                "Named": {"type": "object", "required": ["name"],
                          "properties": {"name": {"oneOf": [
                              {"type": "string", "minLength": 1}, {"type": "null"}]}}}
            }}
        })
    }

    fn check(schema: &str, v: serde_json::Value) -> Vec<String> {
        let d = doc();
        let s = json!({ "$ref": format!("#/components/schemas/{schema}") });
        Validator::new(&d).errors(&s, &v)
    }

    #[test]
    fn integers_are_written_without_a_fraction() {
        assert!(check("Id", json!(3)).is_empty());
        assert_eq!(check("Id", json!(3.0)).len(), 1);
        assert_eq!(check("Id", json!(0)).len(), 1);
        assert_eq!(check("Id", json!("3")).len(), 1);
    }

    #[test]
    fn arrays_have_their_length_and_item_type() {
        assert!(check("Vec3", json!([1, 2.5, -3])).is_empty());
        assert_eq!(check("Vec3", json!([1, 2])).len(), 1);
        assert_eq!(check("Vec3", json!([1, 2, 3, 4])).len(), 1);
        assert_eq!(check("Vec3", json!([1, "2", 3])).len(), 1);
    }

    #[test]
    fn objects_need_required_and_refuse_unknown_properties() {
        assert!(check("Box", json!({"type": "box", "size": [1, 1, 1]})).is_empty());
        let e = check("Box", json!({"type": "box"}));
        assert!(e[0].contains("\"size\""), "{e:?}");
        let e = check(
            "Box",
            json!({"type": "box", "size": [1, 1, 1], "colour": 1}),
        );
        assert!(e[0].contains("\"colour\""), "{e:?}");
    }

    #[test]
    fn one_of_uses_the_discriminator_to_explain() {
        assert!(check("Shape", json!({"type": "ball", "radius": 2})).is_empty());
        let e = check("Shape", json!({"type": "ball", "radius": 0}));
        assert_eq!(e.len(), 1, "{e:?}");
        assert!(e[0].contains("/radius"), "{e:?}");
        let e = check("Shape", json!({"type": "blob"}));
        assert!(e[0].contains("blob"), "{e:?}");
        let e = check("Shape", json!({"size": [1, 1, 1]}));
        assert!(e[0].contains("discriminator"), "{e:?}");
    }

    #[test]
    fn one_of_refuses_two_matches_and_allows_null() {
        assert!(check("Named", json!({"name": null})).is_empty());
        assert!(check("Named", json!({"name": "a"})).is_empty());
        assert!(!check("Named", json!({"name": ""})).is_empty());
        let d = json!({});
        let both = json!({"oneOf": [{"type": "number"}, {"type": "integer"}]});
        assert_eq!(Validator::new(&d).errors(&both, &json!(1)).len(), 1);
    }

    #[test]
    fn unknown_keywords_and_dangling_references_are_schema_problems() {
        let d = doc();
        let v = Validator::new(&d);
        let bad = json!({"type": "string", "contentSchema": {}});
        assert_eq!(v.schema_problems(&bad, "#").len(), 1);
        assert_eq!(v.errors(&bad, &json!("a")).len(), 1);
        let dangling = json!({"$ref": "#/components/schemas/Nope"});
        assert_eq!(v.schema_problems(&dangling, "#").len(), 1);
        let shape = d.pointer("/components/schemas/Shape").unwrap();
        assert!(v.schema_problems(shape, "#").is_empty());
        let mut wrong = shape.clone();
        wrong["discriminator"]["mapping"]["box"] = json!("#/components/schemas/Ball");
        assert!(!v.schema_problems(&wrong, "#").is_empty());
    }
}
