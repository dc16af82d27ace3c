/* motorlab JVM test: run one of the real OpModes against the simulated hub, motor and INA219. */
package org.firstinspires.ftc.teamcode.motorlab.sim;

import com.qualcomm.robotcore.hardware.HardwareMap;
import com.qualcomm.robotcore.util.ElapsedTime;
import java.io.BufferedReader;
import java.io.File;
import java.io.IOException;
import java.io.InputStreamReader;
import java.nio.charset.Charset;
import java.util.HashMap;
import java.util.Locale;
import java.util.Map;
import org.firstinspires.ftc.teamcode.motorlab.DynamicStepOpMode;
import org.firstinspires.ftc.teamcode.motorlab.DynoOpMode;
import org.firstinspires.ftc.teamcode.motorlab.Ina219;
import org.firstinspires.ftc.teamcode.motorlab.QuasistaticOpMode;
import org.firstinspires.ftc.teamcode.motorlab.SpinDownOpMode;
import org.firstinspires.ftc.teamcode.motorlab.SpinUpOpMode;

/**
 * {@code java RunSim experiment=spindown out=DIR seed=1 [drive=relay|hub] [ina=yes|no] [key=value...]}:
 * builds a HardwareMap of simulated devices, runs the OpMode's runOpMode() with its clock driven by the
 * simulation, and prints one JSON line: why it stopped, the log file, the state of the drive at the end
 * and the truth (K, R, J, b, Tf at the counted shaft; cpr).
 *
 * <p>As a robot for motorlab's emulator ({@code motorlab.robot.emulator_jvm}): {@code dashboard=yes}
 * installs {@link SimDashboard} (each telemetry packet printed as a JSON line before the summary),
 * {@code realtime=yes} paces the simulation to the wall clock, and {@code stdin_stop=yes} stops the OpMode
 * (requestOpModeStop, as the Driver Station's STOP) when a line "stop" or the end of stdin arrives.
 */
public final class RunSim {
    private RunSim() {
    }

    public static void main(String[] argv) {
        Map<String, String> a = new HashMap<String, String>();
        for (String arg : argv) {
            int eq = arg.indexOf('=');
            if (eq < 1) {
                throw new IllegalArgumentException("expected key=value, got " + arg);
            }
            a.put(arg.substring(0, eq), arg.substring(eq + 1));
        }
        long seed = Long.parseLong(get(a, "seed", "1"));
        final Plant plant = new Plant();
        plant.K = num(a, "K", plant.K);
        plant.R = num(a, "R", plant.R);
        plant.J = num(a, "J", plant.J);
        plant.b = num(a, "b", plant.b);
        plant.Tf = num(a, "Tf", plant.Tf);
        plant.cpr = num(a, "cpr", plant.cpr);
        plant.supplyVolts = num(a, "supply_V", plant.supplyVolts);
        plant.supplyAmps = num(a, "supply_A", plant.supplyAmps);
        plant.realtime = get(a, "realtime", "no").equals("yes");
        SimHub hub = new SimHub(plant, seed);
        SimIna219 ina = new SimIna219(hub, seed + 1000);

        HardwareMap map = new HardwareMap(null, null);
        map.put("Expansion Hub 2", hub);
        map.put("Expansion Hub 2", new SimDevices.Battery(hub));
        map.put("dyno_motor", new SimDevices.Motor(hub));
        if (get(a, "drive", "relay").equals("relay")) {
            map.put("relay", new SimDevices.Relay(hub));
        }
        if (get(a, "ina", "yes").equals("yes")) {
            map.put("ina219", new Ina219(ina, true));
        }

        final File out = new File(get(a, "out", "."));
        String experiment = get(a, "experiment", "spindown");
        DynoOpMode op = create(experiment, plant, out, a);
        op.config.countsPerRevolution = plant.cpr;
        op.config.maxCurrent = num(a, "max_current", op.config.maxCurrent);
        op.config.maxSpeed = num(a, "max_speed", op.config.maxSpeed);
        op.config.maxTravel = num(a, "max_travel", op.config.maxTravel);
        op.config.maxSeconds = num(a, "max_seconds", op.config.maxSeconds);
        SimTelemetry telemetry = new SimTelemetry(get(a, "print", "no").equals("yes"));
        op.telemetry = telemetry;
        op.hardwareMap = map;
        SimDashboard dashboard = get(a, "dashboard", "no").equals("yes") ? SimDashboard.install(System.out) : null;
        if (get(a, "stdin_stop", "no").equals("yes")) {
            stopOnStdin(op);
        }
        op.runOpMode();

        StringBuilder json = new StringBuilder("{");
        json.append(q("stop_reason")).append(':').append(q(op.stopReason())).append(',');
        json.append(q("log")).append(':').append(op.logFile() == null ? "null" : q(op.logFile().getPath())).append(',');
        json.append(q("rows")).append(':').append(op.rows()).append(',');
        json.append(q("saturated_rows")).append(':').append(op.saturatedRows()).append(',');
        json.append(q("relay_closed")).append(':').append(plant.relayClosed).append(',');
        json.append(q("hub_power")).append(':').append(plant.hubPower).append(',');
        json.append(q("sim_seconds")).append(':').append(plant.seconds()).append(',');
        json.append(q("bulk_reads")).append(':').append(hub.bulkReads).append(',');
        json.append(q("ina_transactions")).append(':').append(ina.transactions).append(',');
        json.append(q("telemetry_updates")).append(':').append(telemetry.updates).append(',');
        json.append(q("dashboard_packets")).append(':').append(dashboard == null ? 0 : dashboard.packets).append(',');
        json.append(q("screen")).append(":[");
        for (int k = 0; k < telemetry.screen().size(); k++) {
            json.append(k > 0 ? "," : "").append(q(telemetry.screen().get(k)));
        }
        json.append("],").append(q("truth")).append(':').append(String.format(Locale.US,
                "{\"K\":%s,\"R\":%s,\"J\":%s,\"b\":%s,\"Tf\":%s,\"cpr\":%s}", plant.K, plant.R, plant.J, plant.b,
                plant.Tf, plant.cpr));
        System.out.println(json.append('}'));
    }

    private static DynoOpMode create(String experiment, final Plant plant, final File out, Map<String, String> a) {
        if (experiment.equals("spindown")) {
            SpinDownOpMode op = new SpinDownOpMode() {
                @Override
                protected ElapsedTime newTimer() {
                    return simulatedTimer(plant);
                }

                @Override
                protected File logDirectory() {
                    return out;
                }

                @Override
                protected void waitForStop() {
                }
            };
            op.runSeconds = num(a, "run_s", 4.0);
            op.coastSeconds = num(a, "coast_s", 20.0);
            op.hubPower = num(a, "hub_power", 1.0);
            return op;
        }
        if (experiment.equals("spinup")) {
            SpinUpOpMode op = new SpinUpOpMode() {
                @Override
                protected ElapsedTime newTimer() {
                    return simulatedTimer(plant);
                }

                @Override
                protected File logDirectory() {
                    return out;
                }

                @Override
                protected void waitForStop() {
                }
            };
            op.runSeconds = num(a, "run_s", 4.0);
            op.hubPower = num(a, "hub_power", 1.0);
            return op;
        }
        if (experiment.equals("quasistatic")) {
            QuasistaticOpMode op = new QuasistaticOpMode() {
                @Override
                protected ElapsedTime newTimer() {
                    return simulatedTimer(plant);
                }

                @Override
                protected File logDirectory() {
                    return out;
                }

                @Override
                protected void waitForStop() {
                }
            };
            op.rampVoltsPerSecond = num(a, "ramp", op.rampVoltsPerSecond);
            op.maxVolts = num(a, "max_V", op.maxVolts);
            op.forward = !get(a, "direction", "forward").equals("backward");
            return op;
        }
        if (experiment.equals("dynamic")) {
            DynamicStepOpMode op = new DynamicStepOpMode() {
                @Override
                protected ElapsedTime newTimer() {
                    return simulatedTimer(plant);
                }

                @Override
                protected File logDirectory() {
                    return out;
                }

                @Override
                protected void waitForStop() {
                }
            };
            op.stepVolts = num(a, "step_V", op.stepVolts);
            op.stepSeconds = num(a, "step_s", op.stepSeconds);
            op.forward = !get(a, "direction", "forward").equals("backward");
            return op;
        }
        throw new IllegalArgumentException("unknown experiment " + experiment);
    }

    /** A line "stop" (or the end of stdin) stops the OpMode, as the Driver Station's STOP does. */
    private static void stopOnStdin(final DynoOpMode op) {
        Thread reader = new Thread(new Runnable() {
            @Override
            public void run() {
                BufferedReader in = new BufferedReader(new InputStreamReader(System.in, Charset.forName("UTF-8")));
                try {
                    String line;
                    do {
                        line = in.readLine();
                    } while (line != null && !line.trim().equals("stop"));
                } catch (IOException e) {
                    // stdin closed: stop
                }
                op.requestOpModeStop();
            }
        }, "stdin-stop");
        reader.setDaemon(true);
        reader.start();
    }

    static ElapsedTime simulatedTimer(final Plant plant) {
        return new ElapsedTime() {
            @Override
            protected long nsNow() {
                return plant.nanos();
            }
        };
    }

    private static String get(Map<String, String> a, String key, String fallback) {
        String v = a.get(key);
        return v == null ? fallback : v;
    }

    private static double num(Map<String, String> a, String key, double fallback) {
        String v = a.get(key);
        return v == null ? fallback : Double.parseDouble(v);
    }

    static String q(String s) {
        StringBuilder b = new StringBuilder("\"");
        for (char c : s.toCharArray()) {
            if (c == '"' || c == '\\') {
                b.append('\\').append(c);
            } else if (c < 0x20) {
                b.append(String.format(Locale.US, "\\u%04x", (int) c));
            } else {
                b.append(c);
            }
        }
        return b.append('"').toString();
    }
}
