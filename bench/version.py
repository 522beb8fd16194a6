"""The tiltbench version, in a leaf module: ``bench.dataset`` records it in every manifest
without importing the ``bench`` package (whose lazy exports would close an import circle)."""

__version__ = "0.1.0"
