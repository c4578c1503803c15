//! Helpers of `tests/contract.rs`: the contract's schemas checked with the `jsonschema`
//! crate plus the project's own rules, a reader of the router's routes, and a real
//! server with an HTTP client.

pub mod routes;
pub mod schema;
pub mod server;
