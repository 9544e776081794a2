"""The building, its bearings and the compiled kernel that integrates them with the rig's hydraulics.

The hydraulics' equations live in :mod:`harness.hydraulics`; the kernel calls them.

Importing the package first drops numba's cached kernels if any kernel source changed
(:func:`harness.model.kernel_cache.drop_stale_kernels`): numba alone would keep a caller
compiled against an older callee in another file.
"""

from harness.model.kernel_cache import drop_stale_kernels

drop_stale_kernels()
