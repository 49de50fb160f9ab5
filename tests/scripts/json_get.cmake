# Prints one value of a JSON file (tests/scripts/slurm_jobs.sh): cmake -DFILE=report.json -DKEY="classes;town" -P
file(READ ${FILE} json)
string(JSON value GET "${json}" ${KEY})
message("${value}")
