"""Helpers the tests share, by concept: small jobs and serial reference maps (``jobs``),
campar and mpirun as child processes (``processes``), stores compared bit for bit
(``stores``), damage done to stores on disk (``damage``), and the tiers' pytest plugin
(``tiers``). Test modules import them as ``from support.jobs import ...``; nothing here
runs at import beyond definitions."""
