//! The application as hyper calls it, counting each request in flight on its connection
//! until the response body is finished or dropped, so a streaming answer (the change
//! stream) keeps its connection busy and out of reach of the idle timeout.

use std::convert::Infallible;
use std::future::Future;
use std::pin::Pin;
use std::sync::Arc;
use std::task::{Context, Poll};

use axum::Router;
use hyper::body::{Bytes, Frame, Incoming, SizeHint};
use hyper::{Request, Response};
use hyper_util::service::TowerToHyperService;

use super::activity::{Activity, Busy};

/// The router, serving one connection whose [`Activity`] it keeps.
#[derive(Clone)]
pub(super) struct Tracking {
    router: TowerToHyperService<Router>,
    activity: Arc<Activity>,
}

impl Tracking {
    /// Serves `router` on the connection described by `activity`.
    pub(super) fn new(router: Router, activity: Arc<Activity>) -> Tracking {
        Tracking {
            router: TowerToHyperService::new(router),
            activity,
        }
    }
}

impl hyper::service::Service<Request<Incoming>> for Tracking {
    type Response = Response<Tracked>;
    type Error = Infallible;
    type Future = Pin<Box<dyn Future<Output = Result<Response<Tracked>, Infallible>> + Send>>;

    /// Postcondition: the request counts as in flight from now until the response body is
    /// dropped (hyper drops it once written, or with the connection), or until this future
    /// is dropped unfinished.
    fn call(&self, req: Request<Incoming>) -> Self::Future {
        let busy = self.activity.begin_request();
        let answer = self.router.call(req);
        Box::pin(async move {
            let res = answer.await?;
            Ok(res.map(|body| Tracked { body, _busy: busy }))
        })
    }
}

/// A response body that keeps its request in flight while it lives.
pub(super) struct Tracked {
    body: axum::body::Body,
    _busy: Busy,
}

impl hyper::body::Body for Tracked {
    type Data = Bytes;
    type Error = axum::Error;

    fn poll_frame(
        self: Pin<&mut Self>,
        cx: &mut Context<'_>,
    ) -> Poll<Option<Result<Frame<Bytes>, axum::Error>>> {
        Pin::new(&mut self.get_mut().body).poll_frame(cx)
    }

    fn is_end_stream(&self) -> bool {
        self.body.is_end_stream()
    }

    fn size_hint(&self) -> SizeHint {
        self.body.size_hint()
    }
}
