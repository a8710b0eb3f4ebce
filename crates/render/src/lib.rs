//! raykit-render (placeholder).
