//! The query parameters each path takes: any other (a misspelt one) is a
//! 400 naming it, as a misspelt field of a JSON body is, so that
//! `PUT /api/resolution?clinet=1` cannot change the default for everyone
//! and `/mjpeg?widht=10` cannot stream at the default size unnoticed.

use crate::api::error;
use axum::extract::{Query, Request};
use axum::http::StatusCode;
use axum::middleware::Next;
use axum::response::Response;

/// The query parameter every path takes: the token check's `?token=`.
pub const TOKEN: &str = "token";

/// The query parameters `path` takes besides [`TOKEN`]; keep in step with
/// the handlers that read a query (`mjpeg::handler`, the camera and
/// resolution API).
pub fn parameters(path: &str) -> &'static [&'static str] {
    match path {
        "/mjpeg" => &["width", "height", "quality", "spp"],
        "/api/camera" | "/api/resolution" => &["client"],
        _ => &[],
    }
}

/// Why `path`'s query `pairs` cannot be used, if they cannot: the
/// parameters the path does not take, named.
pub fn problem(path: &str, pairs: &[(String, String)]) -> Option<String> {
    let known = parameters(path);
    let mut unknown: Vec<&str> = Vec::new();
    for (key, _) in pairs {
        let key = key.as_str();
        if key != TOKEN && !known.contains(&key) && !unknown.contains(&key) {
            unknown.push(key);
        }
    }
    if unknown.is_empty() {
        return None;
    }
    let named = unknown
        .iter()
        .map(|k| format!("'{k}'"))
        .collect::<Vec<_>>()
        .join(", ");
    let noun = if unknown.len() == 1 {
        "parameter"
    } else {
        "parameters"
    };
    let takes = if known.is_empty() {
        format!("{path} takes no query parameters but {TOKEN}")
    } else {
        format!("{path} takes {} and {TOKEN}", known.join(", "))
    };
    Some(format!("unknown query {noun} {named}: {takes}"))
}

/// Middleware: a request whose query holds a parameter its path does not
/// take, or that cannot be decoded, is answered 400 naming it.
pub async fn refuse_unknown(req: Request, next: Next) -> Response {
    if req.uri().query().is_some() {
        let pairs = match Query::<Vec<(String, String)>>::try_from_uri(req.uri()) {
            Ok(Query(pairs)) => pairs,
            Err(e) => return error(StatusCode::BAD_REQUEST, format!("query: {e}")),
        };
        if let Some(p) = problem(req.uri().path(), &pairs) {
            return error(StatusCode::BAD_REQUEST, p);
        }
    }
    next.run(req).await
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pairs(keys: &[&str]) -> Vec<(String, String)> {
        keys.iter().map(|k| (k.to_string(), "1".into())).collect()
    }

    #[test]
    fn only_the_parameters_a_path_takes_pass() {
        assert_eq!(
            problem("/api/resolution", &pairs(&["client", "token"])),
            None
        );
        assert_eq!(problem("/api/status", &pairs(&["token"])), None);
        let p = problem("/api/resolution", &pairs(&["clinet"])).unwrap();
        assert!(p.contains("'clinet'") && p.contains("client"), "{p}");
        let p = problem("/mjpeg", &pairs(&["widht", "height", "widht", "x"])).unwrap();
        assert!(p.contains("'widht', 'x'") && !p.contains("'height'"), "{p}");
        let p = problem("/api/status", &pairs(&["verbose"])).unwrap();
        assert!(
            p.contains("'verbose'") && p.contains("no query parameters"),
            "{p}"
        );
    }
}
