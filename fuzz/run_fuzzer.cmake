# cmake -DFUZZER=... -DCORPUS=dir -DSEEDS="dir;dir" -DDICT=file -DSECONDS=n -DMAXLEN=bytes -DARTIFACTS=dir/ -P run_fuzzer.cmake
# cmake -DFUZZER=... -DREPLAY=dir -P run_fuzzer.cmake
# Fuzz mode: one bounded libFuzzer run: a fixed seed, SECONDS of wall time, 10 s per input
# at most (a longer one is a hang and fails the run), crashes kept in ARTIFACTS and printed in hex.
# A fresh scratch corpus each time: the run depends only on the seeds (tools/fuzz.sh keeps its own).
# Replay mode: every file in REPLAY (the regression inputs in fuzz/crashes/<target>/) runs once,
# 10 s each at most; any crash, sanitizer report, unexpected exception or hang fails.
if(DEFINED REPLAY)
  file(GLOB inputs LIST_DIRECTORIES false ${REPLAY}/*)
  list(FILTER inputs EXCLUDE REGEX "/(README|\\.)[^/]*$")
  list(LENGTH inputs count)
  if(count EQUAL 0)
    message(STATUS "no regression inputs in ${REPLAY}")
    return()
  endif()
  message(STATUS "replaying ${count} regression inputs from ${REPLAY}")
  execute_process(COMMAND ${FUZZER} -timeout=10 -rss_limit_mb=4096 ${inputs} RESULT_VARIABLE result)
  if(NOT result EQUAL 0)
    message(FATAL_ERROR "${FUZZER} failed on a regression input (exit ${result}); the log above names it")
  endif()
  return()
endif()

file(REMOVE_RECURSE ${CORPUS})
file(MAKE_DIRECTORY ${CORPUS} ${ARTIFACTS})
set(seed_dirs)
foreach(dir ${SEEDS})
  if(IS_DIRECTORY ${dir})
    list(APPEND seed_dirs ${dir})
  endif()
endforeach()
execute_process(COMMAND ${FUZZER} -seed=1 -max_total_time=${SECONDS} -timeout=10 -rss_limit_mb=4096
                        -max_len=${MAXLEN} -dict=${DICT} -artifact_prefix=${ARTIFACTS} -print_final_stats=1
                        ${CORPUS} ${seed_dirs}
                RESULT_VARIABLE result)
if(NOT result EQUAL 0)
  # The reproducer in hex, last in the log: a CI log keeps its end, not the artifact.
  # Turn it back into a file with `xxd -r -p hex.txt input`.
  file(GLOB found LIST_DIRECTORIES false ${ARTIFACTS}*)
  foreach(artifact ${found})
    file(READ ${artifact} bytes LIMIT 4096 HEX)
    message("reproducer ${artifact} (first 4096 bytes, hex):\n${bytes}")
  endforeach()
  message(FATAL_ERROR "${FUZZER} found a problem (exit ${result}); reproducer in ${ARTIFACTS}")
endif()
