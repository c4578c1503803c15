//! The contract's schemas, checked with the `jsonschema` crate (JSON Schema 2020-12).
//!
//! A schema of `proto/openapi.yaml` is compiled with the document's `components` beside
//! it, so that its `#/components/...` references resolve; nothing is fetched. `format`
//! is asserted for the formats the crate knows (OpenAPI's `binary` only annotates).
//!
//! The project's own rules, which JSON Schema does not express:
//!
//! - `integer` means a JSON number written without a fraction or exponent (`3`, not
//!   `3.0`), because ids must be JSON integers; the standard counts `3.0` as an integer.
//!   The `type` keyword is the crate's check plus this rule.
//! - A schema uses only keywords the crate asserts, and annotations: OpenAPI 3.0's
//!   `nullable`, a misspelt keyword or `contentSchema` would otherwise be skipped without
//!   a word.
//! - Every name in `required` is one of the object's `properties`; an `enum` lists at
//!   least one value.
//! - OpenAPI's `discriminator` sits beside a `oneOf` of references and maps exactly
//!   those; each mapped schema requires the property and fixes it with `const`, so that
//!   the `oneOf` alone decides what the discriminator says. When no branch matches, the
//!   errors reported are those of the branch the discriminator names.

use jsonschema::error::ValidationErrorKind;
use jsonschema::paths::Location;
use jsonschema::{Keyword, ValidationError};
use serde_json::{Map, Value};

/// Keywords whose value is one schema.
const SUBSCHEMA: &[&str] = &[
    "additionalProperties",
    "items",
    "not",
    "contains",
    "propertyNames",
    "if",
    "then",
    "else",
    "unevaluatedItems",
    "unevaluatedProperties",
];

/// Keywords whose value maps names to schemas.
const SUBSCHEMA_MAP: &[&str] = &["properties", "patternProperties", "dependentSchemas"];

/// Keywords whose value is a list of schemas.
const SUBSCHEMA_LIST: &[&str] = &["allOf", "anyOf", "oneOf", "prefixItems"];

/// The other keywords a schema may use: assertions and annotations.
const KEYWORDS: &[&str] = &[
    "$ref",
    "type",
    "enum",
    "const",
    "required",
    "dependentRequired",
    "minProperties",
    "maxProperties",
    "minItems",
    "maxItems",
    "uniqueItems",
    "minContains",
    "maxContains",
    "minimum",
    "maximum",
    "exclusiveMinimum",
    "exclusiveMaximum",
    "multipleOf",
    "minLength",
    "maxLength",
    "pattern",
    "format",
    "discriminator",
    "description",
    "title",
    "default",
    "examples",
    "example",
    "deprecated",
    "readOnly",
    "writeOnly",
    "$comment",
    "externalDocs",
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

    /// `schema` with the document's components beside it, and its validator.
    fn compile(&self, schema: &Value) -> Result<(Value, jsonschema::Validator), String> {
        let mut root = schema.clone();
        if let (Value::Object(r), Some(c)) = (&mut root, self.doc.get("components")) {
            r.insert("components".into(), c.clone());
        }
        let validator = jsonschema::draft202012::options()
            .offline()
            .should_validate_formats(true)
            .with_keyword("type", type_keyword)
            .build(&root)
            .map_err(|e| format!("{}: {e}", at_or_root(e.instance_path())))?;
        Ok((root, validator))
    }

    /// Every way `instance` fails `schema` (or `schema` breaks the rules above); empty if
    /// it conforms.
    pub fn errors(&self, schema: &Value, instance: &Value) -> Vec<String> {
        let mut errs = Vec::new();
        self.lint(schema, "schema", &mut errs, 0);
        match self.compile(schema) {
            Ok((root, validator)) => {
                for e in validator.iter_errors(instance) {
                    report(&root, &e, "", &mut errs);
                }
            }
            Err(e) => errs.push(format!("schema: {e}")),
        }
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

    /// Problems with a schema itself: what the crate refuses to compile (malformed
    /// keyword values, unresolved references, bad patterns) and the rules above.
    pub fn schema_problems(&self, schema: &Value, at: &str) -> Vec<String> {
        let mut out = Vec::new();
        if let Err(e) = self.compile(schema) {
            out.push(format!("{at}: {e}"));
        }
        self.lint(schema, at, &mut out, 0);
        out
    }

    fn lint(&self, schema: &Value, at: &str, out: &mut Vec<String>, depth: usize) {
        let Value::Object(s) = schema else { return };
        if depth > 64 {
            return;
        }
        for (key, val) in s {
            let here = format!("{at}/{key}");
            let k = key.as_str();
            if SUBSCHEMA.contains(&k) {
                self.lint(val, &here, out, depth + 1);
            } else if SUBSCHEMA_MAP.contains(&k) {
                for (name, sub) in val.as_object().into_iter().flatten() {
                    self.lint(sub, &format!("{here}/{name}"), out, depth + 1);
                }
            } else if SUBSCHEMA_LIST.contains(&k) {
                for (i, sub) in val.as_array().into_iter().flatten().enumerate() {
                    self.lint(sub, &format!("{here}/{i}"), out, depth + 1);
                }
            } else if !KEYWORDS.contains(&k) {
                out.push(format!("{here}: schema keyword {k:?} is not supported"));
            }
        }
        let props = s.get("properties").and_then(Value::as_object);
        for name in s
            .get("required")
            .and_then(Value::as_array)
            .into_iter()
            .flatten()
        {
            if let (Some(n), Some(p)) = (name.as_str(), props)
                && !p.contains_key(n)
            {
                out.push(format!("{at}/required: {n:?} is required but not defined"));
            }
        }
        if s.get("enum")
            .and_then(Value::as_array)
            .is_some_and(Vec::is_empty)
        {
            out.push(format!("{at}/enum: must list at least one value"));
        }
        if let Some(d) = s.get("discriminator") {
            self.lint_discriminator(s, d, &format!("{at}/discriminator"), out);
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

/// An error as `path: message`. A `oneOf` or `anyOf` that nothing matches lists the
/// errors of its branches, or only those of the branch its discriminator names.
fn report(root: &Value, e: &ValidationError, indent: &str, out: &mut Vec<String>) {
    let at = at_or_root(e.instance_path());
    let (word, branches) = match e.kind() {
        ValidationErrorKind::OneOfNotValid { context } => ("oneOf", context),
        ValidationErrorKind::AnyOf { context } => ("anyOf", context),
        ValidationErrorKind::OneOfMultipleValid { .. } => {
            out.push(format!(
                "{indent}{at}: matches more than one branch of oneOf"
            ));
            return;
        }
        _ => {
            out.push(format!("{indent}{at}: {}", brief(&e.to_string())));
            return;
        }
    };
    // The schema holding the keyword, in `root` (every reference points into it).
    let schema_at = e.schema_path().as_str();
    let holder = schema_at
        .strip_suffix(&format!("/{word}"))
        .and_then(|p| root.pointer(p));
    if let Some(d) = holder.and_then(|h| h.get("discriminator")) {
        let prop = d["propertyName"].as_str().unwrap_or("");
        let Some(tag) = e.instance().get(prop).and_then(Value::as_str) else {
            out.push(format!(
                "{indent}{at}: missing discriminator property {prop:?}"
            ));
            return;
        };
        let branch = d["mapping"][tag].as_str().and_then(|t| {
            let one = holder?[word].as_array()?;
            one.iter().position(|b| ref_of(b) == Some(t))
        });
        match branch.and_then(|i| branches.get(i)) {
            Some(errs) => errs.iter().for_each(|e| report(root, e, indent, out)),
            None => out.push(format!(
                "{indent}{at}: {prop} {tag:?} is none of the mapped variants"
            )),
        }
        return;
    }
    out.push(format!("{indent}{at}: matches no branch of {word}"));
    for (i, errs) in branches.iter().enumerate() {
        let inner = format!("{indent}  ({word} branch {i}) ");
        errs.iter().for_each(|e| report(root, e, &inner, out));
    }
}

fn at_or_root(path: &Location) -> &str {
    match path.as_str() {
        "" => "/",
        p => p,
    }
}

/// A message cut to a readable length (messages quote the instance, which may be large).
fn brief(message: &str) -> String {
    const MAX: usize = 400;
    match message.char_indices().nth(MAX) {
        Some((i, _)) => format!("{}…", &message[..i]),
        None => message.to_string(),
    }
}

fn ref_of(v: &Value) -> Option<&str> {
    v.get("$ref").and_then(Value::as_str)
}

/// `type` as the crate checks it, except that a number written with a fraction or an
/// exponent is no `integer`.
struct Type {
    standard: jsonschema::Validator,
    /// `integer` is allowed and `number` is not.
    integer_only: bool,
}

impl Type {
    fn fraction_written(&self, v: &Value) -> bool {
        self.integer_only && v.is_f64()
    }
}

impl<'i> Keyword<'i> for Type {
    fn validate(&self, instance: &'i Value) -> Result<(), ValidationError<'i>> {
        self.standard.validate(instance)?;
        if self.fraction_written(instance) {
            return Err(ValidationError::custom(format!(
                "{instance} is not of type \"integer\" (written with a fraction or exponent)"
            )));
        }
        Ok(())
    }

    fn is_valid(&self, instance: &'i Value) -> bool {
        self.standard.is_valid(instance) && !self.fraction_written(instance)
    }
}

fn type_keyword<'a>(
    _: &'a Map<String, Value>,
    value: &'a Value,
    _: Location,
) -> Result<Box<dyn for<'i> Keyword<'i>>, ValidationError<'a>> {
    let standard = jsonschema::draft202012::new(&serde_json::json!({ "type": value }))
        .map_err(|e| ValidationError::schema(e.to_string()))?;
    let names: Vec<&str> = match value {
        Value::String(n) => vec![n.as_str()],
        Value::Array(a) => a.iter().filter_map(Value::as_str).collect(),
        _ => vec![],
    };
    let integer_only = names.contains(&"integer") && !names.contains(&"number");
    Ok(Box::new(Type {
        standard,
        integer_only,
    }))
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
                              {"type": "string", "minLength": 1}, {"type": "null"}]}}},
                "Colour": {"type": "string", "pattern": "^#[0-9a-f]{6}$"},
                "Name": {"type": "string", "pattern": "^[^\\s\\x00-\\x1f\\u200b-\\u200f]+$"}
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
        let e = check("Id", json!(3.0));
        assert_eq!(e.len(), 1, "{e:?}");
        assert!(e[0].contains("integer"), "{e:?}");
        assert_eq!(check("Id", json!(0)).len(), 1);
        assert_eq!(check("Id", json!("3")).len(), 1);
        let either = json!({"type": ["integer", "null"]});
        let d = json!({});
        assert!(Validator::new(&d).errors(&either, &json!(null)).is_empty());
        assert_eq!(Validator::new(&d).errors(&either, &json!(1.0)).len(), 1);
    }

    #[test]
    fn arrays_have_their_length_and_item_type() {
        assert!(check("Vec3", json!([1, 2.5, -3])).is_empty());
        assert_eq!(check("Vec3", json!([1, 2])).len(), 1);
        assert_eq!(check("Vec3", json!([1, 2, 3, 4])).len(), 1);
        let e = check("Vec3", json!([1, "2", 3]));
        assert_eq!(e.len(), 1, "{e:?}");
        assert!(e[0].starts_with("/1: "), "{e:?}");
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
        assert!(e[0].contains("colour"), "{e:?}");
    }

    #[test]
    fn strings_match_their_pattern() {
        assert!(check("Colour", json!("#00ff7f")).is_empty());
        assert_eq!(check("Colour", json!("00ff7f")).len(), 1);
        assert!(check("Name", json!("table")).is_empty());
        assert_eq!(check("Name", json!("ta ble")).len(), 1);
        assert_eq!(check("Name", json!("ta\u{200b}ble")).len(), 1);
    }

    #[test]
    fn one_of_uses_the_discriminator_to_explain() {
        assert!(check("Shape", json!({"type": "ball", "radius": 2})).is_empty());
        let e = check("Shape", json!({"type": "ball", "radius": 0}));
        assert_eq!(e.len(), 1, "{e:?}");
        assert!(e[0].starts_with("/radius: "), "{e:?}");
        let e = check("Shape", json!({"type": "blob"}));
        assert!(e[0].contains("blob"), "{e:?}");
        let e = check("Shape", json!({"size": [1, 1, 1]}));
        assert!(e[0].contains("discriminator"), "{e:?}");
    }

    #[test]
    fn one_of_refuses_two_matches_and_allows_null() {
        assert!(check("Named", json!({"name": null})).is_empty());
        assert!(check("Named", json!({"name": "a"})).is_empty());
        let e = check("Named", json!({"name": ""}));
        assert!(
            e[0].starts_with("/name: matches no branch of oneOf"),
            "{e:?}"
        );
        let d = json!({});
        let both = json!({"oneOf": [{"type": "number"}, {"type": "integer"}]});
        assert_eq!(Validator::new(&d).errors(&both, &json!(1)).len(), 1);
        assert!(Validator::new(&d).errors(&both, &json!(1.0)).is_empty());
    }

    #[test]
    fn unknown_keywords_and_dangling_references_are_schema_problems() {
        let d = doc();
        let v = Validator::new(&d);
        let bad = json!({"type": "string", "contentSchema": {}});
        assert_eq!(v.schema_problems(&bad, "#").len(), 1);
        assert_eq!(v.errors(&bad, &json!("a")).len(), 1);
        let nullable = json!({"type": "string", "nullable": true});
        assert_eq!(v.schema_problems(&nullable, "#").len(), 1);
        let dangling = json!({"$ref": "#/components/schemas/Nope"});
        assert_eq!(v.schema_problems(&dangling, "#").len(), 1);
        assert_eq!(v.errors(&dangling, &json!(1)).len(), 1);
        let malformed = json!({"type": "int"});
        assert_eq!(v.schema_problems(&malformed, "#").len(), 1);
        let undefined = json!({"type": "object", "required": ["a"], "properties": {}});
        assert_eq!(v.schema_problems(&undefined, "#").len(), 1);
        let shape = d.pointer("/components/schemas/Shape").unwrap();
        assert!(v.schema_problems(shape, "#").is_empty());
        let mut wrong = shape.clone();
        wrong["discriminator"]["mapping"]["box"] = json!("#/components/schemas/Ball");
        assert!(!v.schema_problems(&wrong, "#").is_empty());
    }
}
