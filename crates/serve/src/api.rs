//! The HTTP API: the web client's files, status, scene loading, camera,
//! lights and resolution, and the Prometheus metrics.

use crate::app::AppState;
use crate::client::ClientShared;
use crate::protocol::CameraJson;
use crate::stats::prometheus;
use crate::sync::lock;
use axum::body::Bytes;
use axum::extract::{Query, State};
use axum::http::{header, StatusCode};
use axum::response::{IntoResponse, Response};
use raykit_core::Vec3;
use raykit_render::light_spec::{light_position_problem, point_light};
use serde::Deserialize;
use serde_json::json;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// A JSON error response `{"error": message}`.
pub fn error(status: StatusCode, message: impl Into<String>) -> Response {
    (status, axum::Json(json!({"error": message.into()}))).into_response()
}

/// Every error answer as JSON, as [`error`] writes it: the errors the
/// framework answers itself (a body over the limit, a path or method the
/// server does not have, a WebSocket request without its upgrade) come as
/// plain text or empty, and are rewritten here with their text (or the
/// status's reason) as the message, keeping their other headers (`Allow`).
pub async fn json_errors(req: axum::extract::Request, next: axum::middleware::Next) -> Response {
    let res = next.run(req).await;
    let status = res.status();
    let is_json = res
        .headers()
        .get(header::CONTENT_TYPE)
        .is_some_and(|v| v.as_bytes().starts_with(b"application/json"));
    if is_json || !(status.is_client_error() || status.is_server_error()) {
        return res;
    }
    let (parts, body) = res.into_parts();
    let text = axum::body::to_bytes(body, 64 << 10)
        .await
        .map(|b| String::from_utf8_lossy(&b).trim().to_string())
        .unwrap_or_default();
    let message = match text.is_empty() {
        true => status.canonical_reason().unwrap_or("error").to_lowercase(),
        false => text,
    };
    let mut out = error(status, message);
    for (name, value) in &parts.headers {
        if name != header::CONTENT_TYPE && name != header::CONTENT_LENGTH {
            out.headers_mut().insert(name.clone(), value.clone());
        }
    }
    out
}

/// A request's body read in full within the configured `header_timeout`
/// (counted again from the end of the headers) and `max_message_bytes`,
/// before any handler sees it: a client that sends its body a byte at a
/// time gets 408 and loses its connection instead of holding it, and a
/// body over the limit gets 413 (at once, unread, when its `Content-Length`
/// says so).
pub async fn body_in_time(
    State(state): State<Arc<AppState>>,
    req: axum::extract::Request,
    next: axum::middleware::Next,
) -> Response {
    let (parts, body) = req.into_parts();
    let config = &state.config;
    let limit = config.max_message_bytes;
    // A body announced over the limit is refused at once, unread, instead
    // of waiting for bytes that would be refused anyway.
    let announced = parts
        .headers
        .get(header::CONTENT_LENGTH)
        .and_then(|v| v.to_str().ok())
        .and_then(|v| v.trim().parse::<u64>().ok());
    if let Some(n) = announced.filter(|&n| n > limit as u64) {
        let mut res = error(
            StatusCode::PAYLOAD_TOO_LARGE,
            format!("the request's body is {n} bytes (Content-Length), over the limit of {limit}"),
        );
        res.headers_mut().insert(
            header::CONNECTION,
            header::HeaderValue::from_static("close"),
        );
        return res;
    }
    let read = tokio::time::timeout(config.header_timeout, axum::body::to_bytes(body, limit));
    match read.await {
        Ok(Ok(bytes)) => {
            let req = axum::extract::Request::from_parts(parts, axum::body::Body::from(bytes));
            next.run(req).await
        }
        Ok(Err(_)) => error(
            StatusCode::PAYLOAD_TOO_LARGE,
            format!("the request's body is over {limit} bytes, or was cut off"),
        ),
        Err(_) => {
            let mut res = error(
                StatusCode::REQUEST_TIMEOUT,
                format!(
                    "the request's body did not arrive within {:?}",
                    config.header_timeout
                ),
            );
            res.headers_mut().insert(
                header::CONNECTION,
                header::HeaderValue::from_static("close"),
            );
            res
        }
    }
}

/// A failed request: status and message, answered by [`error`].
pub struct ApiError(pub StatusCode, pub String);

impl IntoResponse for ApiError {
    fn into_response(self) -> Response {
        error(self.0, self.1)
    }
}

/// An optional unsigned integer query parameter.
pub fn query_u32(q: &HashMap<String, String>, key: &str) -> Result<Option<u32>, String> {
    q.get(key)
        .map(|v| {
            v.parse::<u32>()
                .map_err(|_| format!("query parameter {key}='{v}' is not an unsigned integer"))
        })
        .transpose()
}

/// Parse a JSON body into `T`, naming what was wrong.
fn body<T: for<'de> Deserialize<'de>>(bytes: &Bytes) -> Result<T, ApiError> {
    serde_json::from_slice(bytes)
        .map_err(|e| ApiError(StatusCode::BAD_REQUEST, format!("request body: {e}")))
}

/// The client named by `?client=ID`, `None` for the defaults, or a 400/404.
fn target_client(
    state: &AppState,
    q: &HashMap<String, String>,
) -> Result<Option<Arc<ClientShared>>, ApiError> {
    match q.get("client") {
        None => Ok(None),
        Some(id) => {
            let id: u64 = id.parse().map_err(|_| {
                ApiError(
                    StatusCode::BAD_REQUEST,
                    format!("client='{id}' is not a client id"),
                )
            })?;
            if state.client(id).is_some_and(|c| c.kind != "ws") {
                return Err(ApiError(
                    StatusCode::BAD_REQUEST,
                    format!("client {id} is an MJPEG stream, which shows the default camera; leave out ?client="),
                ));
            }
            state.client(id).map(Some).ok_or_else(|| {
                ApiError(
                    StatusCode::NOT_FOUND,
                    format!("no client {id} is connected"),
                )
            })
        }
    }
}

/// Middleware: requests with a body (POST, PUT) must say
/// `Content-Type: application/json` (415 otherwise), which also keeps other
/// web pages from sending them without a CORS preflight.
pub async fn require_json(req: axum::extract::Request, next: axum::middleware::Next) -> Response {
    let needs = matches!(
        *req.method(),
        axum::http::Method::POST | axum::http::Method::PUT
    );
    let is_json = req
        .headers()
        .get(header::CONTENT_TYPE)
        .and_then(|v| v.to_str().ok())
        .is_some_and(|v| {
            v.split(';')
                .next()
                .is_some_and(|t| t.trim().eq_ignore_ascii_case("application/json"))
        });
    if needs && !is_json {
        return error(
            StatusCode::UNSUPPORTED_MEDIA_TYPE,
            "send the request body as JSON with Content-Type: application/json",
        );
    }
    next.run(req).await
}

/// `GET /`.
pub async fn index() -> Response {
    (
        [(header::CONTENT_TYPE, "text/html; charset=utf-8")],
        include_str!("client/index.html"),
    )
        .into_response()
}

/// `GET /client.js`.
pub async fn client_js() -> Response {
    (
        [(header::CONTENT_TYPE, "text/javascript; charset=utf-8")],
        include_str!("client/client.js"),
    )
        .into_response()
}

/// `GET /api/status`.
pub async fn status(State(state): State<Arc<AppState>>) -> Response {
    let world = state.world();
    let g = &world.geometry;
    let now = std::time::Instant::now();
    let clients: Vec<_> = state
        .clients()
        .iter()
        .map(|c| {
            let s = c.sample(now);
            let v = lock(&c.view);
            json!({"client": c.id, "kind": c.kind, "camera": CameraJson::from_camera(&v.camera),
                "full": [v.full.0, v.full.1], "spp": v.spp, "quality": v.quality,
                "frames": s.frames, "fps": s.fps, "latency_ms": s.latency_ms,
                "bytes_per_second": s.bytes_per_second, "inputs": s.inputs, "errors": s.errors})
        })
        .collect();
    let lights: Vec<_> = world
        .lights
        .iter()
        .map(|l| {
            // `color` as PUT /api/lights takes it: irradiance at the centre.
            let at = l.toward(g.bounds.center());
            json!({"kind": l.kind_name(), "position": l.position().map(|p| p.to_array()),
                "direction": (-at.to_light).to_array(), "color": at.irradiance.to_array(),
                "intensity": (at.irradiance * at.distance * at.distance).to_array()})
        })
        .collect();
    let c = &state.config;
    axum::Json(json!({
        "scene": g.scene.name, "triangles": g.scene.mesh.num_triangles(),
        "camera": CameraJson::from_camera(&world.camera), "full": [world.full.0, world.full.1],
        "lights": lights, "clients": clients,
        "limits": {"max_clients": c.max_clients, "max_width": c.max_size.0, "max_height": c.max_size.1,
            "max_spp": c.max_spp, "max_message_bytes": c.max_message_bytes,
            "max_inputs_per_second": c.max_inputs_per_second},
    }))
    .into_response()
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneRequest {
    scene: String,
}

/// Whether `spec` may be loaded: built-in scenes always, files only inside
/// `--scene-dir`. Returns the spec to hand to the loader, and for a file
/// the scene folder as resolved.
fn allowed_scene(state: &AppState, spec: &str) -> Result<(String, Option<PathBuf>), String> {
    if spec.starts_with("builtin:") {
        let max = state.config.max_scene_triangles;
        if let Some(n) = asked_triangles(spec).filter(|&n| n > max as u64) {
            return Err(format!(
                "the scene asks for {n} triangles, more than this server's --max-scene-triangles {max}"
            ));
        }
        return Ok((spec.to_string(), None));
    }
    let Some(dir) = &state.config.scene_dir else {
        return Err("only builtin: scenes can be loaded; start the server with --scene-dir DIR to allow files in DIR".into());
    };
    let root = dir.canonicalize().map_err(|e| {
        // The folder was readable at start (`ServeConfig::problem`); its
        // path stays out of the answer, as everywhere in this API.
        format!(
            "the server's --scene-dir can no longer be read ({e}): it was removed or its \
                 permissions changed after the server started"
        )
    })?;
    // Names that leave the folder are refused before the file system is
    // asked, so that the answer does not tell which files exist elsewhere.
    let leaves = Path::new(spec).components().any(|c| {
        !matches!(
            c,
            std::path::Component::Normal(_) | std::path::Component::CurDir
        )
    });
    if leaves {
        return Err(format!("scene file '{spec}' is outside --scene-dir"));
    }
    let path = root
        .join(Path::new(spec))
        .canonicalize()
        .map_err(|e| format!("scene file '{spec}': {e}"))?;
    if !path.starts_with(&root) {
        return Err(format!("scene file '{spec}' is outside --scene-dir"));
    }
    Ok((path.to_string_lossy().into_owned(), Some(root)))
}

/// Fail when the scene file `path` (named `spec` by the client) reads a
/// file outside `root`: the files it brings in (glTF buffers and images,
/// OBJ material libraries and textures), links followed, stay inside too.
/// Reads the scene file, so it runs with the load, off the async threads.
fn companions_inside(path: &Path, spec: &str, root: &Path) -> anyhow::Result<()> {
    for file in raykit_io::companion_files(path) {
        if file.canonicalize().is_ok_and(|f| !f.starts_with(root)) {
            anyhow::bail!("scene file '{spec}' reads a file outside --scene-dir");
        }
    }
    Ok(())
}

/// The `triangles=N` a built-in scene's specification asks for, so that a
/// request over the server's limit is refused before the scene is built.
fn asked_triangles(spec: &str) -> Option<u64> {
    let (_, params) = spec.strip_prefix("builtin:")?.split_once(':')?;
    params.split(',').find_map(|p| {
        let (key, value) = p.split_once('=')?;
        let digits: String = value.trim().chars().filter(|&c| c != '_').collect();
        (key.trim() == "triangles").then(|| digits.parse().ok())?
    })
}

/// `message` with the scene folder's own path taken out of every file name
/// in it, so that clients see names relative to `--scene-dir` and never
/// where the server keeps its files.
fn relative_to_scene_dir(message: &str, root: &Path) -> String {
    let prefix = format!("{}{}", root.display(), std::path::MAIN_SEPARATOR);
    message
        .replace(&prefix, "")
        .replace(&root.display().to_string(), "--scene-dir")
}

/// `POST /api/scene` with `{"scene": SPEC}`.
pub async fn load_scene(State(state): State<Arc<AppState>>, bytes: Bytes) -> Response {
    let req: SceneRequest = match body(&bytes) {
        Ok(r) => r,
        Err(r) => return r.into_response(),
    };
    let (spec, root) = match allowed_scene(&state, &req.scene) {
        Ok(s) => s,
        Err(e) => return error(StatusCode::BAD_REQUEST, e),
    };
    // The guard moves into the blocking work, so a client that hangs up
    // cannot start a second load while the first still runs.
    let one_at_a_time = state.load_lock.clone().lock_owned().await;
    let loader = state.loader.clone();
    let st = state.clone();
    let folder = root.clone();
    let loaded = tokio::task::spawn_blocking(move || {
        let _held = one_at_a_time;
        let start = std::time::Instant::now();
        if let Some(folder) = &folder {
            companions_inside(Path::new(&spec), &req.scene, folder)?;
        }
        let scene = loader(&spec)?;
        let n = scene.mesh.num_triangles();
        let max = st.config.max_scene_triangles;
        if n > max {
            anyhow::bail!(
                "the scene has {n} triangles, more than this server's --max-scene-triangles {max}"
            );
        }
        Ok((st.set_scene(scene), start.elapsed()))
    })
    .await;
    match loaded {
        Ok(Ok((g, took))) => axum::Json(json!({
            "scene": g.scene.name, "triangles": g.scene.mesh.num_triangles(),
            "load_and_build_ms": took.as_secs_f64() * 1e3,
        }))
        .into_response(),
        Ok(Err(e)) => {
            let message = format!("{e:#}");
            let message = match &root {
                Some(root) => relative_to_scene_dir(&message, root),
                None => message,
            };
            error(StatusCode::BAD_REQUEST, message)
        }
        Err(e) => error(
            StatusCode::INTERNAL_SERVER_ERROR,
            format!("scene loading failed: {e}"),
        ),
    }
}

/// `GET /api/camera[?client=ID]`.
pub async fn get_camera(
    State(state): State<Arc<AppState>>,
    Query(q): Query<HashMap<String, String>>,
) -> Response {
    let camera = match target_client(&state, &q) {
        Ok(Some(c)) => lock(&c.view).camera,
        Ok(None) => state.world().camera,
        Err(r) => return r.into_response(),
    };
    axum::Json(CameraJson::from_camera(&camera)).into_response()
}

/// `PUT /api/camera[?client=ID]` with a camera (fields optional).
pub async fn put_camera(
    State(state): State<Arc<AppState>>,
    Query(q): Query<HashMap<String, String>>,
    bytes: Bytes,
) -> Response {
    let json: CameraJson = match body(&bytes) {
        Ok(j) => j,
        Err(r) => return r.into_response(),
    };
    match target_client(&state, &q) {
        Ok(Some(c)) => match c.set_camera(&json) {
            Ok(cam) => axum::Json(CameraJson::from_camera(&cam)).into_response(),
            Err(e) => error(StatusCode::BAD_REQUEST, e),
        },
        Ok(None) => {
            // Applied to the default inside the world's lock, so two partial
            // updates at once both take effect.
            let result = state.try_update_world(|w| {
                let camera = json.apply(&w.camera);
                match crate::camera_control::camera_problem(&camera) {
                    Some(p) => Err(p.to_string()),
                    None => {
                        w.camera = camera;
                        Ok(camera)
                    }
                }
            });
            match result {
                Ok(camera) => axum::Json(CameraJson::from_camera(&camera)).into_response(),
                Err(p) => error(StatusCode::BAD_REQUEST, p),
            }
        }
        Err(r) => r.into_response(),
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LightJson {
    /// What `GET /api/status` reports; only point lights can be set.
    #[serde(default)]
    kind: Option<String>,
    position: [f32; 3],
    #[serde(default = "white")]
    color: [f32; 3],
    /// Reported by `GET /api/status`, so that its lights can be sent back;
    /// not read (`color` sets the light).
    #[serde(default, rename = "direction")]
    _direction: Option<serde::de::IgnoredAny>,
    /// As `direction`.
    #[serde(default, rename = "intensity")]
    _intensity: Option<serde::de::IgnoredAny>,
}

fn white() -> [f32; 3] {
    [1.0; 3]
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LightsRequest {
    lights: Vec<LightJson>,
}

/// Most lights the API accepts.
pub const MAX_LIGHTS: usize = 64;

/// `PUT /api/lights` with `{"lights": [{"position": [..], "color": [..]}]}`.
pub async fn put_lights(State(state): State<Arc<AppState>>, bytes: Bytes) -> Response {
    let req: LightsRequest = match body(&bytes) {
        Ok(r) => r,
        Err(r) => return r.into_response(),
    };
    if req.lights.len() > MAX_LIGHTS {
        return error(
            StatusCode::BAD_REQUEST,
            format!("at most {MAX_LIGHTS} lights"),
        );
    }
    let center = state.world().geometry.bounds.center();
    let mut lights = Vec::new();
    for (i, l) in req.lights.iter().enumerate() {
        if l.kind.as_deref().is_some_and(|k| k != "point") {
            return error(
                StatusCode::BAD_REQUEST,
                format!("lights[{i}]: only point lights can be set"),
            );
        }
        let (p, c) = (Vec3::from_array(l.position), Vec3::from_array(l.color));
        if let Some(problem) = light_position_problem(p) {
            return error(
                StatusCode::BAD_REQUEST,
                format!("lights[{i}].position: {problem}"),
            );
        }
        if !c.is_finite() || c.min_element() < 0.0 || c.max_element() > 1e6 {
            return error(
                StatusCode::BAD_REQUEST,
                format!("lights[{i}].color must be finite and within 0..=1e6, got {c}"),
            );
        }
        match point_light(p, c, center) {
            Ok(light) => lights.push(light),
            Err(problem) => {
                return error(
                    StatusCode::BAD_REQUEST,
                    format!("lights[{i}].color: {problem}"),
                )
            }
        }
    }
    let n = lights.len();
    state.update_world(|w| w.lights = lights);
    axum::Json(json!({"lights": n})).into_response()
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ResolutionRequest {
    width: u32,
    height: u32,
}

/// `PUT /api/resolution[?client=ID]` with `{"width": W, "height": H}`.
pub async fn put_resolution(
    State(state): State<Arc<AppState>>,
    Query(q): Query<HashMap<String, String>>,
    bytes: Bytes,
) -> Response {
    let req: ResolutionRequest = match body(&bytes) {
        Ok(r) => r,
        Err(r) => return r.into_response(),
    };
    if let Some(p) = state.config.size_problem(req.width, req.height) {
        return error(StatusCode::BAD_REQUEST, p);
    }
    let full = (req.width, req.height);
    match target_client(&state, &q) {
        Ok(Some(c)) => c.set_full(full),
        Ok(None) => state.update_world(|w| w.full = full),
        Err(r) => return r.into_response(),
    }
    axum::Json(json!({"width": full.0, "height": full.1})).into_response()
}

/// `GET /metrics` in the Prometheus text format.
pub async fn metrics(State(state): State<Arc<AppState>>) -> Response {
    let totals = *lock(&state.totals);
    let text = prometheus(
        &state.samples(),
        &totals,
        state.world().geometry.scene.mesh.num_triangles(),
    );
    (
        [(
            header::CONTENT_TYPE,
            "text/plain; version=0.0.4; charset=utf-8",
        )],
        text,
    )
        .into_response()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A loader's error names files relative to the scene folder; other
    /// text stays as it was.
    #[test]
    fn errors_name_files_relative_to_the_scene_folder() {
        let root = Path::new("/srv/raykit/scenes");
        let m = "/srv/raykit/scenes/sub/a.gltf: buffers[0].uri: cannot read \
                 /srv/raykit/scenes/sub/b.bin: no such file";
        assert_eq!(
            relative_to_scene_dir(m, root),
            "sub/a.gltf: buffers[0].uri: cannot read sub/b.bin: no such file"
        );
    }
}
