//! The server's shared state: settings, the world every client renders, the
//! client registry with its limit, totals and the shutdown signal.

use crate::client::ClientShared;
use crate::config::ServeConfig;
use crate::frame::RenderQueue;
use crate::stats::{ClientSample, Totals};
use crate::sync::lock;
use crate::world::{Geometry, World};
use raykit_scene::Scene;
use std::collections::BTreeMap;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex, RwLock};
use std::time::Instant;
use tokio::sync::watch;

/// Loads a scene from a specification (`builtin:NAME[:k=v,...]` or a file
/// path); supplied by the caller so the server does not depend on the file
/// formats.
pub type SceneLoader = Arc<dyn Fn(&str) -> anyhow::Result<Scene> + Send + Sync>;

/// Everything the handlers share.
pub struct AppState {
    /// Settings and limits.
    pub config: ServeConfig,
    /// Scene loading for `POST /api/scene`.
    pub loader: SceneLoader,
    world: RwLock<Arc<World>>,
    world_tx: watch::Sender<u64>,
    clients: Mutex<BTreeMap<u64, Arc<ClientShared>>>,
    next_id: AtomicU64,
    generation: AtomicU64,
    /// Server-wide counters.
    pub totals: Mutex<Totals>,
    shutdown: watch::Sender<bool>,
    /// Held while a scene loads, so only one loads at a time.
    pub load_lock: Arc<tokio::sync::Mutex<()>>,
    /// Where every frame is rendered, in turn, a band at a time.
    pub renderer: RenderQueue,
}

impl AppState {
    /// State around an already prepared first scene.
    pub fn new(config: ServeConfig, loader: SceneLoader, scene: Scene) -> Arc<AppState> {
        let geometry = Arc::new(Geometry::new(scene, 1));
        let aspect = config.full.0 as f32 / config.full.1 as f32;
        let world = World {
            lights: geometry.default_lights(),
            camera: geometry.default_camera(aspect),
            full: config.full,
            geometry,
            version: 1,
            look_version: 1,
        };
        let slice_samples = config
            .slice_samples_per_thread
            .saturating_mul(rayon::current_num_threads() as u64);
        Arc::new(AppState {
            config,
            loader,
            world: RwLock::new(Arc::new(world)),
            world_tx: watch::channel(1).0,
            clients: Mutex::new(BTreeMap::new()),
            next_id: AtomicU64::new(1),
            generation: AtomicU64::new(1),
            totals: Mutex::new(Totals::default()),
            shutdown: watch::channel(false).0,
            load_lock: Arc::new(tokio::sync::Mutex::new(())),
            // Two render threads overlap one frame's JPEG encoding (one
            // thread) with another's tracing (all threads).
            renderer: RenderQueue::new(2, slice_samples),
        })
    }

    /// The current world.
    pub fn world(&self) -> Arc<World> {
        self.world.read().unwrap_or_else(|e| e.into_inner()).clone()
    }

    /// Change the world with `f` (on a copy), bump its version and wake
    /// every client.
    pub fn update_world(&self, f: impl FnOnce(&mut World)) {
        let _ = self.try_update_world(|w| {
            f(w);
            Ok::<(), ()>(())
        });
    }

    /// [`AppState::update_world`] with a change that may be refused: when
    /// `f` returns an error the world stays as it was. `f` runs under the
    /// world's write lock: keep it short.
    pub fn try_update_world<T, E>(
        &self,
        f: impl FnOnce(&mut World) -> Result<T, E>,
    ) -> Result<T, E> {
        let (version, out) = {
            let mut guard = self.world.write().unwrap_or_else(|e| e.into_inner());
            let mut w = (**guard).clone();
            let out = f(&mut w)?;
            w.version = guard.version + 1;
            if !Arc::ptr_eq(&w.geometry, &guard.geometry) || w.lights != guard.lights {
                w.look_version = guard.look_version + 1;
            }
            let v = w.version;
            *guard = Arc::new(w);
            (v, out)
        };
        self.world_tx.send_replace(version);
        Ok(out)
    }

    /// Replace the scene with `scene` (already loaded): new BVH, the scene's
    /// lights and camera.
    pub fn set_scene(&self, scene: Scene) -> Arc<Geometry> {
        let generation = self.generation.fetch_add(1, Ordering::Relaxed) + 1;
        let geometry = Arc::new(Geometry::new(scene, generation));
        // Fitting the camera reads every vertex: do it before taking the lock.
        let full = self.world().full;
        let lights = geometry.default_lights();
        let camera = geometry.default_camera(full.0 as f32 / full.1 as f32);
        let g = geometry.clone();
        self.update_world(move |w| {
            w.lights = lights;
            w.camera = camera;
            w.geometry = g;
        });
        lock(&self.totals).scenes_loaded += 1;
        geometry
    }

    /// Count a frame of `bytes` that took `seconds` to render and encode.
    pub fn count_frame(&self, bytes: usize, seconds: f64) {
        let mut t = lock(&self.totals);
        t.frames += 1;
        t.bytes += bytes as u64;
        t.render_seconds += seconds;
    }

    /// A receiver that changes whenever the world does.
    pub fn watch_world(&self) -> watch::Receiver<u64> {
        self.world_tx.subscribe()
    }

    /// A receiver that turns `true` when the server shuts down.
    pub fn watch_shutdown(&self) -> watch::Receiver<bool> {
        self.shutdown.subscribe()
    }

    /// Ask every session to close.
    pub fn begin_shutdown(&self) {
        self.shutdown.send_replace(true);
    }

    /// Register a new client of `kind` unless the client limit is reached.
    pub fn register(self: &Arc<Self>, kind: &'static str) -> Option<ClientGuard> {
        let mut clients = lock(&self.clients);
        if clients.len() >= self.config.max_clients {
            drop(clients);
            lock(&self.totals).rejected += 1;
            return None;
        }
        let id = self.next_id.fetch_add(1, Ordering::Relaxed);
        let world = self.world();
        let client = Arc::new(ClientShared::new(id, kind, &world, &self.config));
        clients.insert(id, client.clone());
        Some(ClientGuard {
            state: self.clone(),
            client,
        })
    }

    /// The client with `id`, if connected.
    pub fn client(&self, id: u64) -> Option<Arc<ClientShared>> {
        lock(&self.clients).get(&id).cloned()
    }

    /// Every connected client.
    pub fn clients(&self) -> Vec<Arc<ClientShared>> {
        lock(&self.clients).values().cloned().collect()
    }

    /// A snapshot of every client's stats.
    pub fn samples(&self) -> Vec<ClientSample> {
        let now = Instant::now();
        self.clients().iter().map(|c| c.sample(now)).collect()
    }
}

/// A registered client; leaving the registry when dropped.
pub struct ClientGuard {
    state: Arc<AppState>,
    /// The client's shared state.
    pub client: Arc<ClientShared>,
}

impl Drop for ClientGuard {
    fn drop(&mut self) {
        lock(&self.state.clients).remove(&self.client.id);
    }
}
