"""Error analysis: how sensor errors become navigation errors. Python-control error
models (``strapdown_errors``, ``gyrofree_errors``; the integrated filter's own model is
:mod:`gfins_fmi.estimation.error_model`), their covariance, observability and frequency
responses (``covariance``), the noise gains of the 9-accelerometer solution
(``noise_gains``), Monte Carlos of the core on any executor (``montecarlo``) and the
predicted-versus-simulated report of ``gfins analyze`` (``error_report``)."""
