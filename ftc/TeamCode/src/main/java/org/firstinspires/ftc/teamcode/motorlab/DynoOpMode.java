/* motorlab: what every dynamometer OpMode does (set up, log, limits, telemetry). See docs/ftc-robot.md. */
package org.firstinspires.ftc.teamcode.motorlab;

import com.qualcomm.robotcore.eventloop.opmode.LinearOpMode;
import com.qualcomm.robotcore.hardware.DcMotor;
import com.qualcomm.robotcore.util.ElapsedTime;
import java.io.File;
import java.io.IOException;
import java.text.SimpleDateFormat;
import java.util.Date;
import java.util.LinkedHashMap;
import java.util.Locale;
import java.util.Map;
import org.firstinspires.ftc.robotcore.internal.system.AppUtil;

/**
 * The loop shared by the experiments: one bulk read of the encoder (and the INA219) per loop, as fast
 * as the hub answers; each sample written to the log at once; the limits checked; then the
 * experiment's {@link #step(Sample)} commands the drive. Whatever ends the loop (done, a limit, the
 * INA219's over-voltage refusal, STOP, an exception), the relay opens and the hub power goes to 0.
 *
 * <p>Each loop reads the encoder with one bulk read, the voltage (relay drive: the INA219 just before
 * the encoder; hub drive: the command in effect, just after) and the current, then commands the drive.
 * Sample time: the midpoint of the bulk read, from the OpMode's start [s]. Timing offsets of about one
 * hub transaction remain (docs/ftc-robot.md, "Timing").
 */
public abstract class DynoOpMode extends LinearOpMode {
    public final DynoConfig config = new DynoConfig();
    protected DynoRig rig;
    private String stopReason = "not started";
    private File logFile;
    private int rows;
    private int saturated;
    private Publisher dashboard;

    /**
     * Where each sample goes besides the log and the Driver Station: FTC Dashboard's telemetry
     * ({@link DashboardTelemetry}, when that file is in the project and Dashboard runs).
     */
    public interface Publisher {
        /** False when there is nowhere to publish to (Dashboard not started). */
        boolean isActive();

        /** One sample; {@code power}: the voltage and current are measured (the log's columns). */
        void publish(Sample s, boolean power, double batteryVolts, double countsPerRevolution);
    }

    /** Experiment name written in the header ({@code # experiment:}) and the file name. */
    protected abstract String experiment();

    /** Add this experiment's parameters to the header. */
    protected abstract void describe(Map<String, String> fields);

    /** Command the drive after sample {@code s}; return false when the experiment is complete. */
    protected abstract boolean step(Sample s);

    /** Why this rig cannot run the experiment, or null. */
    protected String checkRig() {
        return null;
    }

    /** True when the log carries the voltage and current columns. */
    protected boolean powerColumns() {
        return true;
    }

    /** What the motor does when it is stopped at the end (FLOAT coasts; BRAKE holds a mechanism). */
    protected DcMotor.ZeroPowerBehavior endBehaviour() {
        return DcMotor.ZeroPowerBehavior.FLOAT;
    }

    /** The run clock (a test drives it from a simulated time). */
    protected ElapsedTime newTimer() {
        return new ElapsedTime();
    }

    /** Where logs go: /sdcard/FIRST/motorlab on the controller. */
    protected File logDirectory() {
        return new File(AppUtil.FIRST_FOLDER, config.folder);
    }

    /**
     * FTC Dashboard's publisher, found by name so that a project without Dashboard (and without
     * DashboardTelemetry.java) compiles and runs these OpModes as they are; null when there is none.
     */
    protected Publisher dashboard() {
        String name = DynoOpMode.class.getName().replace("DynoOpMode", "DashboardTelemetry");
        try {
            Publisher publisher = (Publisher) Class.forName(name).getDeclaredConstructor().newInstance();
            return publisher.isActive() ? publisher : null;
        } catch (ReflectiveOperationException e) {
            return null; // DashboardTelemetry.java deleted: no Dashboard in this project
        } catch (LinkageError e) {
            return null; // compiled against Dashboard, but its library is not on this robot
        }
    }

    /** After the run, keep the result on the Driver Station until STOP. */
    protected void waitForStop() {
        while (opModeIsActive()) {
            sleep(50);
        }
    }

    @Override
    public void runOpMode() {
        telemetry.addData("motorlab", "%s: setting up", experiment());
        telemetry.update();
        String problem;
        try {
            rig = DynoRig.open(hardwareMap, config);
            problem = checkRig();
            if (problem == null && rig.ina219 != null) {
                rig.ina219.readBusVoltage(); // refuses now if the supply is already above the limit
            }
        } catch (RuntimeException e) {
            problem = e.getMessage();
        }
        showInit(problem);
        waitForStart();
        if (problem != null) {
            stopReason = "refused: " + problem;
            if (rig != null) {
                rig.stop(endBehaviour());
            }
        } else if (!isStopRequested()) {
            run();
        }
        showResult();
        waitForStop();
    }

    private void run() {
        Sample s = new Sample();
        DynoLog log = null;
        stopReason = "running";
        try {
            log = new DynoLog(new File(logDirectory(), fileName()), header(), powerColumns());
            logFile = log.file();
            rig.readEncoder(s);
            dashboard = dashboard();
            Limits limits = new Limits(config, s.counts);
            ElapsedTime clock = newTimer();
            double lastTelemetry = -1.0;
            while (opModeIsActive()) {
                boolean relay = rig.drive == DynoRig.Drive.RELAY;
                if (relay) {
                    rig.readVoltage(s); // measured: just before the encoder latch
                }
                double before = clock.seconds();
                rig.readEncoder(s);
                s.time = 0.5 * (before + clock.seconds());
                if (!relay) {
                    rig.readVoltage(s); // the command in effect since the last loop, × the battery now
                }
                rig.readCurrent(s);
                if (rig.ina219 != null && (rig.ina219.isSaturated(s.current) || rig.ina219.overflowed())) {
                    saturated++; // the row is still written: the count is shown at the end
                }
                log.write(s);
                if (dashboard != null) {
                    dashboard.publish(s, powerColumns(), rig.lastBatteryVoltage(), config.countsPerRevolution);
                }
                String reason = limits.check(s);
                if (reason == null && config.stopOnB && gamepad1 != null && gamepad1.b) {
                    reason = "stopped with gamepad 1 B";
                }
                if (reason != null) {
                    stopReason = "limit: " + reason;
                    break;
                }
                if (!step(s)) {
                    stopReason = "complete";
                    break;
                }
                if (s.time - lastTelemetry >= 0.25) {
                    lastTelemetry = s.time;
                    showRun(s, log.rows());
                }
            }
            if (stopReason.equals("running")) {
                stopReason = "stopped from the Driver Station";
            }
        } catch (Ina219.OverVoltageException e) {
            stopReason = e.getMessage();
        } catch (IOException e) {
            stopReason = "log file: " + e.getMessage();
        } catch (RuntimeException e) {
            stopReason = "error: " + e;
        } finally {
            rig.stop(endBehaviour());
            if (log != null) {
                rows = log.rows();
                try {
                    log.close();
                } catch (IOException e) {
                    stopReason += "; log file not closed: " + e.getMessage();
                }
            }
        }
    }

    private String fileName() {
        return "motorlab-" + experiment() + "-" + new SimpleDateFormat("yyyyMMdd-HHmmss", Locale.US).format(new Date())
                + ".txt";
    }

    private Map<String, String> header() {
        Map<String, String> f = new LinkedHashMap<String, String>();
        f.put("experiment", experiment());
        f.put("motor", config.motor);
        f.put("cpr", fmt(config.countsPerRevolution));
        f.put("gear_ratio", fmt(config.gearRatio));
        f.put("drive", rig.drive == DynoRig.Drive.RELAY ? "relay" : "hub");
        if (rig.drive == DynoRig.Drive.RELAY) {
            f.put("voltage", "INA219 bus voltage");
            f.put("current", "INA219 shunt current");
        } else {
            f.put("voltage", "commanded: power x hub input voltage");
            f.put("current", rig.ina219 != null ? "INA219 shunt current" : "hub motor current, signed by the power");
        }
        if (rig.ina219 != null) {
            Ina219.Parameters p = rig.ina219.getParameters();
            f.put("ina219_shunt_ohm", fmt(p.shuntOhms));
            f.put("ina219_current_lsb_A", String.format(Locale.US, "%.6g", rig.ina219.getCurrentLsb()));
            f.put("ina219_adc", p.busAdc + "/" + p.shuntAdc);
            f.put("ina219_max_bus_V", fmt(p.maxBusVoltage));
        }
        f.put("limits", String.format(Locale.US, "%.0f s, %.2f A, %.0f counts/s, %.0f counts", config.maxSeconds,
                config.maxCurrent, config.maxSpeed, config.maxTravel));
        describe(f);
        Class<?> named = getClass();
        while (named.isAnonymousClass()) {
            named = named.getSuperclass();
        }
        f.put("opmode", named.getSimpleName());
        f.put("started", new SimpleDateFormat("yyyy-MM-dd'T'HH:mm:ss", Locale.US).format(new Date()));
        return f;
    }

    protected static String fmt(double value) {
        return value == Math.rint(value) && Math.abs(value) < 1e15 ? String.valueOf((long) value) : String.valueOf(value);
    }

    private void showInit(String problem) {
        telemetry.addData("motorlab", experiment());
        if (rig != null) {
            telemetry.addData("drive", rig.drive == DynoRig.Drive.RELAY ? "relay + bench supply" : "hub port");
            telemetry.addData("devices", "motor '%s', %d hub(s), INA219 %s, relay %s", config.motorName, rig.hubs.size(),
                    rig.ina219 != null ? "yes" : "no", rig.relay != null ? "yes" : "no");
        }
        telemetry.addData("motor", "%s, %s counts/rev, ratio %s", config.motor, fmt(config.countsPerRevolution),
                fmt(config.gearRatio));
        telemetry.addData("log folder", logDirectory().getPath());
        telemetry.addData("FTC Dashboard", dashboard() != null ? "publishing each sample" : "not running");
        telemetry.addData(">", problem == null ? "Press START (gamepad 1 B stops)" : "CANNOT RUN: " + problem);
        telemetry.update();
    }

    private void showRun(Sample s, int rowCount) {
        telemetry.addData("t", "%.2f s", s.time);
        telemetry.addData("encoder", "%d counts, %.0f counts/s", s.counts, s.velocity);
        telemetry.addData("power", "%.3f V, %.3f A", s.voltage, s.current);
        telemetry.addData("rows", rowCount);
        telemetry.update();
    }

    private void showResult() {
        telemetry.addData("motorlab", "%s: %s", experiment(), stopReason);
        if (saturated > 0) {
            telemetry.addData("WARNING", "%d rows with the INA219 at the end of its current range (%.2f A): "
                    + "use a smaller shunt or a lower current limit", saturated,
                    rig.ina219.getParameters().shuntRange.volts / rig.ina219.getParameters().shuntOhms);
        }
        if (logFile != null) {
            telemetry.addData("log", "%d rows in %s", rows, logFile.getPath());
            telemetry.addData("pull", "adb pull %s", logFile.getPath());
        }
        telemetry.update();
    }

    /** Why the run ended ("complete", "limit: ...", the INA219's refusal, ...). */
    public String stopReason() {
        return stopReason;
    }

    /** The log written by the last run, or null. */
    public File logFile() {
        return logFile;
    }

    public int rows() {
        return rows;
    }

    /** Rows whose current was at the end of the INA219's range (clipped). */
    public int saturatedRows() {
        return saturated;
    }
}
