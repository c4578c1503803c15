//! The API contract: `proto/openapi.yaml`, compiled in and served as JSON.

use std::sync::OnceLock;

/// The OpenAPI 3.1 document as written.
pub const OPENAPI_YAML: &str = include_str!("../../proto/openapi.yaml");

/// The OpenAPI document as JSON text (parsed once).
pub fn openapi_json() -> String {
    static JSON: OnceLock<String> = OnceLock::new();
    JSON.get_or_init(|| match openapi_value() {
        Ok(v) => v.to_string(),
        Err(e) => serde_json::json!({ "error": format!("proto/openapi.yaml: {e}") }).to_string(),
    })
    .clone()
}

/// The OpenAPI document as a JSON value.
pub fn openapi_value() -> Result<serde_json::Value, serde_norway::Error> {
    serde_norway::from_str(OPENAPI_YAML)
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_contract_parses_as_openapi_3_1() {
        let v = super::openapi_value().expect("proto/openapi.yaml is YAML");
        assert_eq!(v["openapi"].as_str().map(|s| &s[..3]), Some("3.1"));
        assert!(v["paths"].as_object().is_some_and(|p| !p.is_empty()));
    }
}
