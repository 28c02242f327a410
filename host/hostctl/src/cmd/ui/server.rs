//! The HTTP side of `hostctl ui` (axum on tokio): the page and its assets (embedded in the
//! binary from `host/ui/`), the WebSocket at `/ws` ([`super::ws`]), `POST /api/cmd` (the same
//! commands as over the WebSocket) and `POST /api/map` (a `hostctl map` JSON to view).
//!
//! Invariants: every request passes [`super::security`]'s rules first (one Host, an
//! origin-form target, Host, Origin, and the token for everything but the static assets and
//! the favicon), so a refused request never reaches a handler, and a refused WebSocket is
//! never upgraded. Every answer, refusals included, carries `X-Content-Type-Options:
//! nosniff`. The page allows only its own origin (Content-Security-Policy `default-src
//! 'self'`): it loads nothing from elsewhere and works offline. Request bodies are limited
//! ([`MAX_MAP_BYTES`], [`MAX_CMD_BYTES`]): a larger `Content-Length` is answered `413` before
//! the body is read, and a chunked body is cut off at the limit with the same `413`.

use super::app::{reply_json, submit, App};
use super::conn::Busy;
use super::security::{check_form, token_from_query, Guard, Refusal, TOKEN_HEADER};
use super::wire::parse_command;
use super::ws::ws;
use axum::body::Bytes;
use axum::extract::{DefaultBodyLimit, Request as HttpRequest, State};
use axum::http::{header, HeaderValue, StatusCode};
use axum::middleware::{self, Next};
use axum::response::{IntoResponse, Response};
use axum::routing::{get, post};
use axum::Extension;
use axum::Router;
use serde_json::json;
use stiffwall_analysis::live::plane;
use tower_http::limit::RequestBodyLimitLayer;

/// The page, its script and its style, embedded at build time.
pub const INDEX_HTML: &str = include_str!("../../../ui/index.html");
/// The page's script.
pub const APP_JS: &str = include_str!("../../../ui/app.js");
/// The page's style.
pub const STYLE_CSS: &str = include_str!("../../../ui/style.css");

/// Largest map JSON accepted by `POST /api/map` (4 MiB: about 220 bytes per grid point, so
/// ≈ 19 000 points, e.g. the default 34 × 21 grid (≈ 160 kB per panel) in 25 panels).
pub const MAX_MAP_BYTES: usize = 4 << 20;
/// Largest command accepted by `POST /api/cmd` (as over the WebSocket).
pub const MAX_CMD_BYTES: usize = super::ws::MAX_WS_MESSAGE;

/// The router of one run.
pub fn router(app: App) -> Router {
    Router::new()
        .route("/", get(index))
        .route("/app.js", get(app_js))
        .route("/style.css", get(style_css))
        .route("/favicon.ico", get(StatusCode::NO_CONTENT))
        .route("/ws", get(ws))
        .route("/api/cmd", post(api_cmd).layer(body_limit(MAX_CMD_BYTES)))
        .route("/api/map", post(api_map).layer(body_limit(MAX_MAP_BYTES)))
        .layer(middleware::from_fn_with_state(app.clone(), guard))
        .with_state(app)
}

/// The body limit of a route: `413` by `Content-Length` before reading, or at the limit while
/// reading a chunked body (the extractor's own limit is the same).
fn body_limit(bytes: usize) -> (RequestBodyLimitLayer, DefaultBodyLimit) {
    (
        RequestBodyLimitLayer::new(bytes),
        DefaultBodyLimit::max(bytes),
    )
}

fn refused(why: &Refusal) -> Response {
    let status = StatusCode::from_u16(why.status()).unwrap_or(StatusCode::FORBIDDEN);
    let reason = status.canonical_reason().unwrap_or("");
    (
        status,
        [(header::CONTENT_TYPE, "text/plain; charset=utf-8")],
        format!("{} {reason}: {why}\n", status.as_u16()),
    )
        .into_response()
}

/// The rules of [`super::security`], in order.
fn check(guard: &Guard, req: &HttpRequest) -> Result<(), Refusal> {
    let h = req.headers();
    check_form(h.get_all(header::HOST).iter().count(), req.uri())?;
    let text = |name: header::HeaderName| h.get(name).and_then(|v| v.to_str().ok());
    let host = text(header::HOST);
    let origin = text(header::ORIGIN);
    let public = matches!(req.uri().path(), "/app.js" | "/style.css" | "/favicon.ico");
    let token = h
        .get(TOKEN_HEADER)
        .and_then(|v| v.to_str().ok())
        .or_else(|| token_from_query(req.uri().query()));
    if public {
        guard.check_site(host, origin)
    } else {
        guard.check(host, origin, token)
    }
}

async fn guard(State(app): State<App>, req: HttpRequest, next: Next) -> Response {
    let mut resp = match check(&app.guard, &req) {
        Ok(()) => {
            let mut resp = next.run(req).await;
            let hs = resp.headers_mut();
            hs.insert(
                header::CONTENT_SECURITY_POLICY,
                HeaderValue::from_static(
                    "default-src 'self'; connect-src 'self'; img-src 'self' data:; frame-ancestors 'none'",
                ),
            );
            hs.insert(header::X_FRAME_OPTIONS, HeaderValue::from_static("DENY"));
            hs.insert(header::CACHE_CONTROL, HeaderValue::from_static("no-store"));
            hs.insert(
                header::REFERRER_POLICY,
                HeaderValue::from_static("no-referrer"),
            );
            resp
        }
        Err(e) => refused(&e),
    };
    resp.headers_mut().insert(
        header::X_CONTENT_TYPE_OPTIONS,
        HeaderValue::from_static("nosniff"),
    );
    resp
}

async fn index() -> impl IntoResponse {
    (
        [(header::CONTENT_TYPE, "text/html; charset=utf-8")],
        INDEX_HTML,
    )
}

async fn app_js() -> impl IntoResponse {
    (
        [(header::CONTENT_TYPE, "text/javascript; charset=utf-8")],
        APP_JS,
    )
}

async fn style_css() -> impl IntoResponse {
    (
        [(header::CONTENT_TYPE, "text/css; charset=utf-8")],
        STYLE_CSS,
    )
}

async fn api_cmd(State(app): State<App>, busy: Option<Extension<Busy>>, body: Bytes) -> Response {
    match parse_command(&body) {
        Ok(env) => {
            let id = env.id.clone();
            // A release test or a tune may take minutes: the connection is not idle meanwhile.
            let _busy = busy.map(|b| b.hold());
            let r = submit(&app, env, super::control::API_CLIENT).await;
            let status = if r.is_ok() {
                StatusCode::OK
            } else {
                StatusCode::UNPROCESSABLE_ENTITY
            };
            (status, axum::Json(reply_json(&id, r))).into_response()
        }
        Err((id, e)) => {
            (StatusCode::BAD_REQUEST, axum::Json(reply_json(&id, Err(e)))).into_response()
        }
    }
}

async fn api_map(body: Bytes) -> Response {
    let text = String::from_utf8_lossy(&body);
    match plane::map_view(&text) {
        Ok(v) => axum::Json(v).into_response(),
        Err(e) => (
            StatusCode::UNPROCESSABLE_ENTITY,
            axum::Json(json!({"type": "map", "error": format!("{:#}", anyhow::Error::from(e))})),
        )
            .into_response(),
    }
}
