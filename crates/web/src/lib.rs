//! The browser build.
