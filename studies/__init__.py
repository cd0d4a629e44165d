"""The study scripts of tippedisk_analysis: one module per study, ``main(output_dir, quick=False)``
writes its datasets and figures to ``output_dir`` and prints what it found.

Installed with the package as ``tippedisk_studies``; run one with ``tippedisk study NAME``
(``--quick``: a reduced size for smoke tests) or ``python -m tippedisk_studies.NAME [DIR]``.
"""
