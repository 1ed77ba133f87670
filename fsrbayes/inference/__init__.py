"""Inference layer: likelihood, posterior, emcee sampling, diagnostics."""

from .likelihood import LIKELIHOODS, SpecimenData, log_likelihood_pointwise
from .posterior import LogPosterior

__all__ = ["LIKELIHOODS", "SpecimenData", "log_likelihood_pointwise", "LogPosterior"]
