# Runs a windowed app (penumbra-view, or penumbra-demo with FRAMES_FLAG=--screenshot-frames)
# under xvfb-run and checks that it wrote a screenshot of a plausible size.
# EXTRA: more arguments, separated by spaces (penumbra-view --virtual-debug ...).
if(NOT FRAMES_FLAG)
  set(FRAMES_FLAG --frames)
endif()
separate_arguments(extra UNIX_COMMAND "${EXTRA}")
file(REMOVE ${OUT})
execute_process(COMMAND ${XVFB_RUN} -a -s "-screen 0 800x600x24" ${VIEW} --scene box --width 800 --height 600
                        --screenshot ${OUT} ${FRAMES_FLAG} 3 ${extra}
                RESULT_VARIABLE rc ERROR_VARIABLE err TIMEOUT 170)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "${VIEW} exited with ${rc}: ${err}")
endif()
file(SIZE ${OUT} size)
if(size LESS 8000)  # a blank 800x600 PNG is under 3 kB; the box scene with the panel is ~15 kB
  message(FATAL_ERROR "screenshot ${OUT} is only ${size} bytes: the window looks empty")
endif()
