//! A bound on large responses prepared at once: a basin file's grid, a finished window, a sweep
//! or design table can take hundreds of megabytes while serialised (a 4-million-cell basin is
//! about 20 MB of JSON). At most `permits` are prepared and sent at once, `queue` more wait;
//! a request beyond those is answered 503 at once, before any work. A permit is held until the
//! response's bytes are dropped (sent, or the client gone), not only while they are built.

use crate::error::ApiError;
use axum::body::{Body, Bytes};
use axum::http::header;
use axum::response::{IntoResponse, Response};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;
use tokio::sync::{OwnedSemaphorePermit, Semaphore};

/// Two large responses at once, four more waiting.
pub const DEFAULT: (usize, usize) = (2, 4);

/// The gate.
pub struct Heavy {
    sem: Arc<Semaphore>,
    /// Requests holding or waiting for a permit.
    inside: Arc<AtomicUsize>,
    permits: usize,
    queue: usize,
}

/// A place inside the gate (holding or waiting): counted until dropped.
pub struct Place {
    inside: Arc<AtomicUsize>,
}

impl Drop for Place {
    fn drop(&mut self) {
        self.inside.fetch_sub(1, Ordering::SeqCst);
    }
}

/// A permit to prepare and send one large response.
pub struct Permit {
    _permit: OwnedSemaphorePermit,
    _place: Place,
}

impl Heavy {
    /// A gate of `permits` (at least 1) and `queue` waiting places.
    pub fn new(permits: usize, queue: usize) -> Heavy {
        let permits = permits.max(1);
        Heavy {
            sem: Arc::new(Semaphore::new(permits)),
            inside: Arc::new(AtomicUsize::new(0)),
            permits,
            queue,
        }
    }

    /// A permit, waiting for one if fewer than `permits + queue` requests are inside; else 503.
    pub async fn enter(&self) -> Result<Permit, ApiError> {
        let n = self.inside.fetch_add(1, Ordering::SeqCst);
        let place = Place {
            inside: self.inside.clone(),
        };
        if n >= self.permits + self.queue {
            return Err(ApiError::unavailable(format!(
                "busy: {} large responses are being prepared and {} more wait (the bound); \
                 try again",
                self.permits, self.queue
            )));
        }
        let permit = self
            .sem
            .clone()
            .acquire_owned()
            .await
            .map_err(|_| ApiError::internal("the response gate is closed"))?;
        Ok(Permit {
            _permit: permit,
            _place: place,
        })
    }

    /// A permit now, or `None` when all are taken (for tests that fill the gate).
    pub fn try_enter(&self) -> Option<Permit> {
        let permit = self.sem.clone().try_acquire_owned().ok()?;
        self.inside.fetch_add(1, Ordering::SeqCst);
        Some(Permit {
            _permit: permit,
            _place: Place {
                inside: self.inside.clone(),
            },
        })
    }
}

/// JSON bytes that keep their permit until dropped.
struct Owned(Vec<u8>, #[allow(dead_code)] Permit);

impl AsRef<[u8]> for Owned {
    fn as_ref(&self) -> &[u8] {
        &self.0
    }
}

/// A JSON response of `bytes` holding `permit` until hyper has sent (or dropped) it.
pub fn response(bytes: Vec<u8>, permit: Permit) -> Response {
    let body = Body::from(Bytes::from_owner(Owned(bytes, permit)));
    ([(header::CONTENT_TYPE, "application/json")], body).into_response()
}
