"""steamtwin: a digital twin of a steam turbine in deep peak-shaving operation."""

from steamtwin.cache import configure_jit_cache

__version__ = "0.1.0"

configure_jit_cache()
