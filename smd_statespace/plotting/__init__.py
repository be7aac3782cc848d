"""Figures: :mod:`.cycles` (convergence, parameters against the bouncing frequency, comparisons),
:mod:`.population` (histograms with skew-normal fits, trends) and :mod:`.check` (a model check's fit
and residual diagnostics, drawn by :meth:`smd_statespace.diagnostics.ModelCheck.plot_fit` and
:meth:`~smd_statespace.diagnostics.ModelCheck.plot_diagnostics`)."""
