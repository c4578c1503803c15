//! Helpers of `tests/contract.rs`: a JSON Schema validator for the subset the contract
//! uses, a reader of the router's routes, and a real server with an HTTP client.

pub mod routes;
pub mod schema;
pub mod server;
