//! `raykit._raykit`: the extension module under the `raykit` Python
//! package. Each function converts numpy arrays, releases the GIL and
//! makes one call into the raykit crates; the Open3D- and trimesh-shaped
//! classes are written in Python on top of it (`python/raykit/`).

mod arrays;
mod cull;
mod errors;
mod geotiff;
mod hit_arrays;
mod image_order;
mod instances;
mod mesh_io;
mod near_rays;
mod queries;
mod render;
mod scene;
mod terrain;
mod threads;

use pyo3::prelude::*;

/// The raykit engine: scenes and ray queries, mesh files, terrain,
/// culling and rendering.
#[pymodule]
fn _raykit(m: &Bound<'_, PyModule>) -> PyResult<()> {
    threads::note_loading_process();
    m.add_class::<scene::Scene>()?;
    m.add_class::<instances::InstancedScene>()?;
    m.add("INVALID_ID", hit_arrays::INVALID_ID)?;
    m.add("MAX_COORDINATE", raykit_core::MAX_COORDINATE)?;
    m.add_function(wrap_pyfunction!(mesh_io::load_mesh, m)?)?;
    m.add_function(wrap_pyfunction!(mesh_io::load_gltf_instances, m)?)?;
    m.add_function(wrap_pyfunction!(near_rays::near_rays, m)?)?;
    m.add_function(wrap_pyfunction!(queries::closest_points, m)?)?;
    m.add_function(wrap_pyfunction!(queries::distance, m)?)?;
    m.add_function(wrap_pyfunction!(queries::signed_distance, m)?)?;
    m.add_function(wrap_pyfunction!(queries::occupancy, m)?)?;
    m.add_function(wrap_pyfunction!(queries::winding_number, m)?)?;
    m.add_function(wrap_pyfunction!(queries::count_intersections, m)?)?;
    m.add_function(wrap_pyfunction!(queries::list_intersections, m)?)?;
    m.add_function(wrap_pyfunction!(terrain::load_dem, m)?)?;
    m.add_function(wrap_pyfunction!(terrain::shadow, m)?)?;
    m.add_function(wrap_pyfunction!(terrain::check_lights, m)?)?;
    m.add_function(wrap_pyfunction!(terrain::default_views, m)?)?;
    m.add_function(wrap_pyfunction!(terrain::cast, m)?)?;
    m.add_function(wrap_pyfunction!(render::render, m)?)?;
    m.add_function(wrap_pyfunction!(geotiff::write_geotiff, m)?)?;
    m.add_function(wrap_pyfunction!(cull::cull, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
