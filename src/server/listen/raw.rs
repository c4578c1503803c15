//! Whole HTTP/1.1 answers written by the connection layer itself, outside hyper and axum:
//! a [`Problem`] as `application/problem+json` on a connection about to close.

use crate::server::problem::Problem;

/// `problem` as a complete HTTP/1.1 answer: the status line, `content-type:
/// application/problem+json`, `content-length`, `retry-after` if the problem has one,
/// `connection: close`, then `extra` (whole header lines, each ending in CRLF, or empty),
/// a blank line and the problem's JSON body.
///
/// Precondition: `extra` holds only well-formed header lines.
pub(super) fn answer(problem: &Problem, extra: &[u8]) -> Vec<u8> {
    let body = problem.to_json();
    let status = problem.status;
    let mut out = Vec::with_capacity(160 + extra.len() + body.len());
    out.extend_from_slice(
        format!(
            "HTTP/1.1 {} {}\r\ncontent-type: application/problem+json\r\ncontent-length: {}\r\n",
            status.as_u16(),
            status.canonical_reason().unwrap_or("Error"),
            body.len()
        )
        .as_bytes(),
    );
    if let Some(seconds) = problem.retry_after {
        out.extend_from_slice(format!("retry-after: {seconds}\r\n").as_bytes());
    }
    out.extend_from_slice(b"connection: close\r\n");
    out.extend_from_slice(extra);
    out.extend_from_slice(b"\r\n");
    out.extend_from_slice(&body);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_problem_becomes_a_closing_problem_json_answer() {
        let p = Problem::busy("too many open connections", 1);
        let text = String::from_utf8(answer(&p, b"date: Thu, 01 Jan 2030 00:00:00 GMT\r\n"))
            .expect("text");
        let (head, body) = text.split_once("\r\n\r\n").expect("a head and a body");
        let lines: Vec<&str> = head.split("\r\n").collect();
        assert_eq!(lines[0], "HTTP/1.1 503 Service Unavailable");
        assert!(lines.contains(&"content-type: application/problem+json"));
        assert!(lines.contains(&"retry-after: 1"));
        assert!(lines.contains(&"connection: close"));
        assert!(lines.contains(&"date: Thu, 01 Jan 2030 00:00:00 GMT"));
        assert!(lines.contains(&format!("content-length: {}", body.len()).as_str()));
        let json: serde_json::Value = serde_json::from_str(body).expect("JSON");
        assert_eq!(json["status"], 503);
        assert_eq!(json["detail"], "too many open connections");
    }
}
