"""Figures: :mod:`.cycles` (convergence, parameters against the bouncing frequency, comparisons) and
:mod:`.population` (histograms with skew-normal fits, trends). Model checks draw their own
(:meth:`smd_statespace.diagnostics.ModelCheck.plot_diagnostics`)."""
