"""Monte Carlo campaigns: many dispersed flights, open or closed loop, resumable.

- :mod:`.dispersions`: the distributions of the dispersed quantities and their seeded draws;
- :mod:`.spec`: what every run flies (:class:`Campaign`) and the run table's columns;
- :mod:`.run`: one run of a campaign (:func:`run_one`);
- :mod:`.engines`: where runs execute (serial, local processes, a dask cluster);
- :mod:`.runner`: :func:`run_campaign`, resumable over its run table, with progress;
- :mod:`.run_table`: the CSV run table (:class:`RunTable`); :mod:`.progress`: progress lines;
- :mod:`.summary`: statistics of a run table (:func:`campaign_summary`).
"""

from lightcraft_opt.campaign.dispersions import DISPERSED, Dispersions, Normal, Uniform
from lightcraft_opt.campaign.engines import dask_cluster, local_processes, serial
from lightcraft_opt.campaign.run import RunOutcome, run_one
from lightcraft_opt.campaign.run_table import RunTable, read_table
from lightcraft_opt.campaign.runner import CampaignResult, run_campaign
from lightcraft_opt.campaign.spec import Campaign
from lightcraft_opt.campaign.summary import campaign_summary

__all__ = [
    "DISPERSED",
    "Campaign",
    "CampaignResult",
    "Dispersions",
    "Normal",
    "RunOutcome",
    "RunTable",
    "Uniform",
    "campaign_summary",
    "dask_cluster",
    "local_processes",
    "read_table",
    "run_campaign",
    "run_one",
    "serial",
]
