"""pcsuite's converters package: problems, methods, models and analysis (see the README's Layout)."""
from . import kernel_cache

kernel_cache.refresh()   # before any compiled kernel loads its cache (see converters.kernel_cache)
